"""Do the gyros turn as the star tracker does? Angle, axis, direction and units of each maneuver's
rotation, a unit slip's likely cause, a reference sampled too sparsely, and a gyro that clips."""

import numpy as np

from gyrocal.checks.sensing import (
    CHECK_BLOCK_S,
    FIT_COLUMNS,
    MAX_TURN_BETWEEN_REFERENCE_DEG,
    Sensed,
    blocked_sums,
    comparable,
    consistent,
    consistent_any,
    fit_rotation,
    gyro_at_st,
    interval_rotations,
    neighbour_residual,
    nominal_body_increments,
    reference_noise_rad,
    response,
)
from gyrocal.finding import Findings
from gyrocal.io.telemetry import Campaign
from gyrocal.model.units import AXES, AXIS_INDEX, rad_to_arcsec

__all__ = [
    "ALTERNATIVES", "GROSS_SCALE", "MAX_TURN_BETWEEN_REFERENCE_DEG", "path_ratio", "rotation_findings", "too_little",
    "too_short", "undersampled"
]

ALTERNATIVES = (
    (180.0 / np.pi, "increments in degrees rather than radians?"),
    (1e3, "increments 1000 times too large (mrad rather than rad?)"),
    (1e-3, "increments 1000 times too small (krad? a unit slip?)"),
)
"""Gyro scale factors a unit slip produces, with the likely cause; rates-for-increments and
cumulative angles are tried as well (they depend on the sample rate)."""



GROSS_SCALE = (0.5, 2.0)
"""How far the gyros' path may run from the reference's (`path_ratio`) before a unit is suspected, where
the response check found no positive evidence: a fault that scales the gyros by 57 or 1000 scatters the
response so widely (or wraps their composed rotations) that no direction is determined and the check
passes for want of evidence. Where a direction is determined and fits, the ratio is not asked: a wobble
about a circling axis within a sparse reference's interval shortens the sums of increments by half."""


def path_ratio(sensed: Sensed) -> float:
    """The gyros' path over the reference's: the lengths of their increments summed per interval (linear
    in the gyros' scale, never wrapped) over those of the reference's rotations, on the intervals where
    the reference turns at least a quarter of its turn's 99th percentile and ten times its own noise (the
    reference alone says where: the noise of the two sensors' difference is the fault's, where there is
    one); 1 where it never turns."""
    turn = np.linalg.norm(sensed.d_st, axis=1)
    own_noise = 1.4826 * float(np.median(np.abs(neighbour_residual(sensed.d_st)))) if len(turn) > 2 else 0.0
    turning = turn >= max(0.25 * np.percentile(turn, 99), 10.0 * np.sqrt(3.0) * own_noise) if len(turn) else turn > 0
    if not turning.any() or not turn[turning].sum():
        return 1.0
    return float(np.linalg.norm(sensed.d_gyro[turning], axis=1).sum() / np.linalg.norm(sensed.d_st[turning], axis=1).sum())


def too_little(where: str, maneuver, turned_rad: float, min_angle_rad: float) -> str:
    """The refusal of a maneuver that turns too little for any scale factor: how far it turns, and how
    far it must (the reference's noise over the scale factor's prior sd)."""
    what = ("neither the reference nor the gyros rotate" if np.rad2deg(turned_rad) < 1.0 else
            f"the reference and the gyros turn at most {np.rad2deg(turned_rad):.3g} deg")
    return (f"{where}: {what} in [{maneuver.t_start}, {maneuver.t_end}] s, where a scale factor needs at least "
            f"{np.rad2deg(min_angle_rad):.2g} deg (the reference's noise over the prior's sd) to be told better than "
            "its prior: a hold, or a motion too small to calibrate on")


def too_short(where: str) -> str:
    """The warning for a maneuver too short to hold the gyros' rotation against the reference's."""
    return (f"{where}: too short to hold the gyros' rotation against the reference's (at most {FIT_COLUMNS} "
            f"blocks of {CHECK_BLOCK_S:g} s, as many as the fit's columns): not checked")


def rotation_findings(campaign: Campaign, sensed: Sensed, limits, findings: Findings) -> bool:
    """Angle, axis, direction and units of one maneuver's rotation, gyro against star tracker;
    whether it is consistent. A free-motion maneuver (no axis label) is compared as a 3x3 response
    (`free_rotation_findings`)."""
    m = campaign.maneuver(sensed.data.id)
    if m.free:
        return free_rotation_findings(campaign, sensed, limits, findings)
    a = AXIS_INDEX[m.axis]
    sf_bound, mis_bound, sf_sd = limits
    d_st, dt, d_gyro = sensed.d_st, sensed.dt, sensed.d_gyro
    where = sensed.where
    min_angle = reference_noise_rad(sensed) / sf_sd
    blocked_dt, blocked_gyro, blocked_st = blocked_sums(dt, d_gyro, d_st)
    fit = fit_rotation(blocked_gyro, blocked_st, blocked_dt, a)
    gyro_excursion = np.ptp(np.cumsum(d_gyro, axis=0), axis=0)
    if fit.excursion_rad.max() < min_angle and gyro_excursion.max() < min_angle:
        findings.refuse("rotation", too_little(where, m, max(fit.excursion_rad.max(), gyro_excursion.max()), min_angle))
        return False
    if len(blocked_dt) <= FIT_COLUMNS:
        findings.warn("rotation", too_short(where))
        return True
    if consistent(d_gyro, d_st, dt, a, sf_bound, mis_bound):
        n_errors = len(findings.errors)
        if fit.excursion_rad[a] < min_angle:
            findings.refuse("rotation", f"{where}: the star tracker rotates only {np.rad2deg(fit.excursion_rad[a]):.3g} deg "
                                   f"about {m.axis}; a scale factor needs {np.rad2deg(min_angle):.2g} deg")
        elif m.direction == "both":
            turned = {"+": d_st[:, a].clip(min=0).sum(), "-": -d_st[:, a].clip(max=0).sum()}
            missing = [s for s in "+-" if turned[s] < min_angle]
            if missing:
                findings.refuse("rotation", f"{where}: labelled both, but the star tracker turns only "
                                       f"{np.rad2deg(turned[missing[0]]):.3g} deg in the {missing[0]} direction")
        elif np.sign(fit.net_rad) != m.sign:
            findings.refuse("rotation",
                f"{where}: the star tracker and the gyros turn {np.rad2deg(fit.net_rad):+.1f} deg about {m.axis}, "
                f"the opposite of the label's direction {m.direction!r}")
        return len(findings.errors) == n_errors
    st_axis = AXES[fit.axis]
    if st_axis != m.axis and AXES[int(np.argmax(gyro_excursion))] != m.axis:
        findings.refuse("rotation",
            f"{where}: the star tracker and the gyros both rotate mostly about {st_axis} "
            f"({np.rad2deg(fit.excursion_rad[fit.axis]):.1f} deg), not {m.axis}: is the maneuver's axis label wrong?")
        return False
    hint = _diagnose(campaign, sensed, a, sf_bound, mis_bound) or undersampled(sensed)
    if hint:
        findings.refuse("rotation", f"{where}: {hint}")
        return False
    response = ", ".join(f"{AXES[b]} {fit.response[b]:+.4g}" for b in range(3))
    findings.refuse("rotation",
        f"{where}: per unit of the star tracker's rotation about {m.axis} the gyros turn {response} "
        f"(physical: {m.axis} 1 +/- {sf_bound:.2g}, the others within {rad_to_arcsec(mis_bound):.0f} arcsec); "
        f"the star tracker rotates mostly about {st_axis}. Check the channel columns, their axes in "
        f"campaign.yaml and the star tracker's mounting")
    return False


def free_rotation_findings(campaign: Campaign, sensed: Sensed, limits, findings: Findings) -> bool:
    """One free-motion maneuver's rotation, gyro against reference, for any motion: the 3x3 response
    (`sensing.response`) must have its scale near 1 and small cross terms on every axis the motion
    determines, within the physical bounds (`sensing.physical_limits`). Otherwise a unit slip, a
    flipped channel, swapped axes, a cumulative angle or a quaternion order is named where one
    explains it (`_diagnose` with no axis); whether it is consistent."""
    sf_bound, mis_bound, sf_sd = limits
    where = sensed.where
    m = campaign.maneuver(sensed.data.id)
    noise = reference_noise_rad(sensed)
    min_angle = noise / sf_sd
    st_excursion = np.ptp(np.cumsum(sensed.d_st, axis=0), axis=0)
    gyro_excursion = np.ptp(np.cumsum(sensed.d_gyro, axis=0), axis=0)
    if st_excursion.max() < min_angle and gyro_excursion.max() < min_angle:
        findings.refuse("rotation", too_little(where, m, max(st_excursion.max(), gyro_excursion.max()), min_angle))
        return False
    keep = comparable(sensed.d_gyro)
    first = response(sensed.d_gyro_turned, sensed.d_st, sensed.dt, sf_bound, noise_rad=noise, keep=keep)
    if first.short:
        findings.warn("rotation", too_short(where))
        return True
    accepted = consistent_any(sensed.d_gyro_turned, sensed.d_st, sensed.dt, sf_bound, mis_bound, noise, keep=keep)
    ratio = path_ratio(sensed)
    if not (accepted and first.determined.any()) and not GROSS_SCALE[0] <= ratio <= GROSS_SCALE[1]:
        cause = next((c for factor, c in ALTERNATIVES if abs(ratio / factor - 1.0) < 0.1),
                     "check the gyro columns' unit in the mapping, and that they are increments")
        findings.refuse("rotation", f"{where}: the gyros' path is {ratio:.4g} times the reference's where it turns: "
                                    f"{cause}")
        return False
    if accepted:
        return True
    hint = _diagnose(campaign, sensed, None, sf_bound, mis_bound) or undersampled(sensed)
    if hint:
        findings.refuse("rotation", f"{where}: {hint}")
        return False
    def vector(v):
        return "[" + ", ".join(f"{x:+.4g}" for x in v) + "]"

    rows = "; ".join(f"per unit about {vector(first.directions[:, k])}: {vector(first.matrix[:, k])}"
                     for k in np.flatnonzero(first.determined))
    findings.refuse("rotation",
        f"{where}: the gyros' rotation, body axes, "
        f"{f'({rows})' if rows else 'determined along no direction of the motion'} (physical: the direction "
        f"itself, its scale within 1 +/- {sf_bound:.2g}, the misalignments within {rad_to_arcsec(mis_bound):.0f} "
        "arcsec). Check the channel columns, their axes in campaign.yaml and the reference's mounting")
    return False


def _agrees(d_gyro, d_st, dt, axis, sf_bound, mis_bound, noise_rad=0.0) -> bool:
    """`consistent` about the labelled ``axis``, or for free motion (``axis`` None) `consistent_any`."""
    if axis is None:
        return consistent_any(d_gyro, d_st, dt, sf_bound, mis_bound, noise_rad, need_determined=True)
    return consistent(d_gyro, d_st, dt, axis, sf_bound, mis_bound)


def _diagnose(campaign, sensed: Sensed, a, sf_bound, mis_bound) -> str:
    """The likely cause of an inconsistent rotation: the first reinterpretation that makes it consistent.
    ``a``: the labelled axis, or None for free motion (every axis the motion determines is compared,
    each axis's sign is tried, and so is each pair of axes swapped)."""
    data, d_gyro, d_st, dt = sensed.data, sensed.d_gyro, sensed.d_st, sensed.dt
    noise = reference_noise_rad(sensed)

    along = int(np.argmax(np.ptp(np.cumsum(d_st, axis=0), axis=0))) if a is None else a
    scale = np.ptp(np.cumsum(d_gyro[:, along])) / np.ptp(np.cumsum(d_st[:, along]))
    dt_gyro = float(np.median(data.dt))
    candidates = list(ALTERNATIVES) + [
        (1.0 / dt_gyro, f"rates in rad/s rather than increments? ({1 / dt_gyro:.4g} is the gyro's sample rate)"),
        (180.0 / np.pi / dt_gyro, "rates in deg/s rather than increments in rad?")]
    for factor, cause in candidates:
        if _agrees(d_gyro / factor, d_st, dt, a, sf_bound, mis_bound, noise):
            return f"the gyro rotation is {scale:.4g} times the star tracker's: {cause}"
    for flipped in (range(3) if a is None else (a,)):
        negated = d_gyro * np.where(np.arange(3) == flipped, -1.0, 1.0)
        if _agrees(negated, d_st, dt, a, sf_bound, mis_bound, noise):
            channel = data.sets[sensed.set_index][flipped]
            signed = float(d_gyro[:, flipped] @ d_st[:, flipped] / (d_st[:, flipped] @ d_st[:, flipped]))
            return (f"channel {channel} turns opposite to the star tracker about {AXES[flipped]} ({signed:+.4g} times "
                    "its rotation): its sign is flipped. Negate its column in gyro.csv, or check its axis in "
                    "campaign.yaml")
    if a is None:
        for i, j in ((0, 1), (0, 2), (1, 2)):
            swapped = d_gyro[:, [j if k == i else i if k == j else k for k in range(3)]]
            if _agrees(swapped, d_st, dt, a, sf_bound, mis_bound, noise):
                first, second = data.sets[sensed.set_index][i], data.sets[sensed.set_index][j]
                return (f"the gyros' {AXES[i]} and {AXES[j]} rotations match the star tracker's {AXES[j]} and "
                        f"{AXES[i]}: channels {first} and {second} look swapped. Check their axes in campaign.yaml "
                        "and their columns in gyro.csv")
    i0 = int(np.searchsorted(campaign.gyro_time, data.gyro_time[0]))
    raw = campaign.increments(slice(i0, i0 + len(data.gyro_time)))
    differenced = gyro_at_st(data, nominal_body_increments(data, np.diff(raw, axis=0), sensed.set_index))
    if _agrees(differenced, d_st, dt, a, sf_bound, mis_bound, noise):
        return ("the gyro columns hold a cumulative angle, not the increment since the previous row: "
                "their differences match the star tracker")
    for order, cause in (([1, 2, 3, 0], "scalar first (q0, q1, q2, q3)"), ([3, 0, 1, 2], "in another order")):
        d_reordered = interval_rotations(data.st_quat[:, order])
        if _agrees(d_gyro, d_reordered, dt, a, sf_bound, mis_bound, noise):
            return (f"the star-tracker quaternions look {cause}: read in that order they match the gyros; "
                    "the contract's q1..q4 are scalar last (docs/interface.md section 1)")
    return ""


def undersampled(sensed: Sensed) -> str:
    """Why the reference is sampled too sparsely for this maneuver's motion, or "": where the
    gyro turns more than `MAX_TURN_BETWEEN_REFERENCE_DEG` between two reference samples, the
    reference's own rotation there may be wrapped by whole turns. Asked only once the rotation
    check has failed and no unit slip explains it (a slip also makes the gyro's turn look
    large); the answer gives the interval the gyro's peak rate needs, or, where only gaps in the
    reference (samples flagged invalid) span such turns, names the gap: those intervals are left out
    of the check (`sensing.comparable`), so the rest failed it. A gyro that turns that far within one
    of its own samples is not told to wait for a denser reference: its own data are suspect (a
    cumulative angle, a unit), and the generic rotation message stands."""
    turn_deg = np.rad2deg(np.linalg.norm(sensed.d_gyro, axis=1))
    worst = int(np.argmax(turn_deg))
    if turn_deg[worst] <= MAX_TURN_BETWEEN_REFERENCE_DEG:
        return ""
    peak_deg_s = np.rad2deg(np.max(np.linalg.norm(sensed.body, axis=1) / sensed.data.dt))
    if MAX_TURN_BETWEEN_REFERENCE_DEG / peak_deg_s < np.median(sensed.data.dt):
        return ""
    beyond = int(np.sum(turn_deg > MAX_TURN_BETWEEN_REFERENCE_DEG))
    spacing = np.diff(sensed.data.st_time)
    step = float(np.median(spacing))
    gap = float(spacing[worst])
    if np.all(spacing[turn_deg > MAX_TURN_BETWEEN_REFERENCE_DEG] > 1.5 * step):  # gaps alone, not the interval
        return (f"the gyro turns {turn_deg[worst]:.0f} deg between the reference samples at "
                f"{sensed.data.st_time[worst]:.6g} s and {sensed.data.st_time[worst + 1]:.6g} s, {gap:.2g} s apart where "
                f"the reference is every {step:.2g} s: its samples between are missing (flagged invalid; markers lost "
                f"during a fast turn), and the rotation across the gap is ambiguous ({beyond} intervals beyond "
                f"{MAX_TURN_BETWEEN_REFERENCE_DEG:.0f} deg). Left out, the rest of the maneuver still does not match "
                "the gyros; check the channel columns, their axes and the reference's mounting")
    return (f"the gyro turns {turn_deg[worst]:.0f} deg between the reference samples at {sensed.data.st_time[worst]:.6g} s "
            f"and {sensed.data.st_time[worst + 1]:.6g} s ({beyond} intervals beyond {MAX_TURN_BETWEEN_REFERENCE_DEG:.0f} "
            "deg): the reference's rotation between samples is ambiguous there, so its rotation cannot be checked "
            f"against the gyro's. At the gyro's peak rate, {peak_deg_s:.0f} deg/s, keep the reference at least every "
            f"{MAX_TURN_BETWEEN_REFERENCE_DEG / peak_deg_s:.2g} s (gyrocal import --reference-interval)")
