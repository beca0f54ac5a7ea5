"""The reference's mounting: the rotation taking its frame into body axes, declared (applied as declared,
never replaced: refused where the data disagree) or estimated from the data (docs/interface.md)."""

from dataclasses import replace

import numpy as np
from scipy.spatial.transform import Rotation

from gyrocal.checks.sensing import comparable, physical_limits, sense
from gyrocal.finding import Finding, Status
from gyrocal.inference.fit.identification import DETECTION_SD
from gyrocal.io.telemetry import Campaign
from gyrocal.maneuvers import preprocess
from gyrocal.model.units import AXES

__all__ = ["ALTERNATIVES", "align", "aligned", "carried", "estimate_mounting", "judge_declared"]


def estimate_mounting(campaign: Campaign) -> tuple:
    """Coarse alignment of the attitude reference: the rotation taking its frame into body axes that
    best maps its interval rotations onto the gyros' (Wahba's problem, `Rotation.align_vectors`; the
    gyros' increments composed, the intervals too long to compare left out: `sensing.comparable`),
    over every maneuver, and the sd of its angle about each body axis (deg). It absorbs the
    common rotation of the gyro misalignments too: after it, misalignments are relative to the
    reference as the data align it. About an axis no maneuver turns across, it is not determined."""
    sensed = [sense(preprocess.slice_maneuver(campaign, m.id)) for m in campaign.maneuvers]
    keep = [comparable(s.d_gyro) for s in sensed]  # a turn beyond a quarter between samples may be wrapped
    if sum(int(k.sum()) for k in keep) < 3:  # too few left to align: every interval, as the rotations read
        keep = [np.ones(len(s.d_gyro), dtype=bool) for s in sensed]
    gyro = np.vstack([s.d_gyro_turned[k] for s, k in zip(sensed, keep)])
    reference = np.vstack([s.d_st[k] for s, k in zip(sensed, keep)])
    mounting, rssd, sensitivity = Rotation.align_vectors(gyro, reference, return_sensitivity=True)
    variance = rssd**2 / max(len(gyro) - 3, 1)
    return mounting, np.rad2deg(np.sqrt(np.diag(sensitivity) * variance))


def aligned(campaign: Campaign, mounting: Rotation) -> Campaign:
    """The campaign with its reference attitudes turned into body axes: ``R_body = R_ref M^-1`` for a
    mounting ``M`` that takes reference-frame vectors into body axes."""
    quat = campaign.st_quat.copy()
    valid = campaign.st_valid == 1
    quat[valid] = (Rotation.from_quat(quat[valid]) * mounting.inv()).as_quat()
    return replace(campaign, st_quat=quat)


def align(campaign: Campaign) -> tuple:
    """The reference's mounting from ``campaign.yaml`` (``star_tracker.mounting``): a declared
    quaternion, applied as declared and never replaced; or ``estimate``: the data's alignment.
    Returns the aligned campaign, what was applied, and for a declared mounting the finding that
    refuses it where the data disagree beyond what misalignments can carry (`judge_declared`)."""
    declared = campaign.star_tracker.get("mounting")
    if declared is None:
        return campaign, {}, None
    if declared == "estimate":
        mounting, sd_deg = estimate_mounting(campaign)
        applied = {"quat": mounting.as_quat().tolist(), "source": "estimated from the data",
                   "angle_deg": float(np.rad2deg(mounting.magnitude())),
                   "sd_deg": {a: float(v) for a, v in zip(AXES, sd_deg)}}
        return aligned(campaign, mounting), applied, None
    mounting = Rotation.from_quat(declared)
    residual, residual_sd = estimate_mounting(aligned(campaign, mounting))
    applied = {"quat": mounting.as_quat().tolist(), "source": "nominal (campaign.yaml)",
               "angle_deg": float(np.rad2deg(mounting.magnitude())),
               "residual_deg": {a: float(v) for a, v in zip(AXES, np.rad2deg(residual.as_rotvec()))}}
    return aligned(campaign, mounting), applied, judge_declared(campaign, mounting, residual, residual_sd)


def carried(residual: Rotation, residual_sd_deg, mis_bound_rad: float) -> bool:
    """Whether misalignments within their physical bound can carry a residual rotation between the
    gyro triad and the reference: about each body axis the rotation is half the difference of two
    opposite misalignments, so at most ``mis_bound_rad``, give or take `DETECTION_SD` of its sd."""
    excess = np.abs(residual.as_rotvec()) - mis_bound_rad - DETECTION_SD * np.deg2rad(residual_sd_deg)
    return bool(np.all(excess <= 0))


ALTERNATIVES = (
    ("its conjugate (the inverse convention: body axes into the reference frame)", lambda q: Rotation.from_quat(q).inv()),
    ("it read scalar first, [q0, q1, q2, q3]", lambda q: Rotation.from_quat(np.roll(q, -1))),
    ("its conjugate read scalar first", lambda q: Rotation.from_quat(np.roll(q, -1)).inv()),
)
"""Conventions a declared mounting may have been written in, each with how to read it."""


def judge_declared(campaign: Campaign, mounting: Rotation, residual: Rotation, residual_sd_deg):
    """None where the declared mounting agrees with the data, within what misalignments can carry;
    otherwise the refusal: by how much and about which axes the data disagree, whether another
    common convention of the same quaternion fits, and what to write instead."""
    mis_bound = physical_limits(campaign.channels, campaign.gyro.get("sensor_class"))[1]
    if carried(residual, residual_sd_deg, mis_bound):
        return None
    off_deg = np.rad2deg(residual.as_rotvec())
    about = ", ".join(f"{a} {v:+.3f}" for a, v in zip(AXES, off_deg))
    declared = mounting.as_quat()
    fits = []
    for name, read in ALTERNATIVES:
        other = read(declared)
        rest, rest_sd = estimate_mounting(aligned(campaign, other))
        if carried(rest, rest_sd, mis_bound):
            fits.append(f"{name} fits: write mounting: {np.round(other.as_quat(), 9).tolist()}")
    corrected = np.round((residual * mounting).as_quat(), 9).tolist()
    todo = ("; ".join(fits) if fits else "no other common convention of it fits either") + (
        f". Otherwise write mounting: estimate (misalignments are then relative to the reference as the data "
        f"align it), or the data's alignment, mounting: {corrected}")
    return Finding("mounting", Status.REFUSE,
                   f"campaign.yaml: star_tracker.mounting, applied as declared, leaves the reference turned from the "
                   f"gyros by {np.rad2deg(residual.magnitude()):.3f} deg (about {about} deg), more than misalignments "
                   f"within their bound ({np.rad2deg(mis_bound) * 3600:.0f} arcsec each) can carry. {todo[0].upper()}{todo[1:]}",
                   figure=float(np.rad2deg(residual.magnitude())), threshold=float(np.rad2deg(mis_bound)), unit="deg",
                   action=todo, where="star_tracker.mounting")
