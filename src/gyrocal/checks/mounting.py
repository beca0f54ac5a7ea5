"""The reference's mounting: the rotation taking its frame into body axes, declared or estimated."""

from dataclasses import replace

import numpy as np
from scipy.spatial.transform import Rotation

from gyrocal.checks.sensing import physical_limits, sense
from gyrocal.inference import preprocess
from gyrocal.io.telemetry import Campaign
from gyrocal.model.units import AXES

__all__ = ["align", "aligned", "estimate_mounting"]


def estimate_mounting(campaign: Campaign) -> tuple:
    """Coarse alignment of the attitude reference: the rotation taking its frame into body axes that
    best maps its interval rotations onto the gyros' (Wahba's problem, `Rotation.align_vectors`),
    over every maneuver, and the sd of its angle about each body axis (deg). It absorbs the
    common rotation of the gyro misalignments too: after it, misalignments are relative to the
    reference as the data align it. About an axis no maneuver turns across, it is not determined."""
    sensed = [sense(preprocess.slice_maneuver(campaign, m.id)) for m in campaign.maneuvers]
    gyro, reference = np.vstack([s.d_gyro for s in sensed]), np.vstack([s.d_st for s in sensed])
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
    """The reference's mounting from ``campaign.yaml`` (``star_tracker.mounting``): a nominal
    quaternion, refined by the data's coarse alignment when it is off by more than the largest
    misalignment; or ``estimate``: the data's alignment alone. Returns the aligned campaign
    and what was applied."""
    declared = campaign.star_tracker.get("mounting")
    if declared is None:
        return campaign, {}
    sd_deg = None
    if declared == "estimate":
        (mounting, sd_deg), source = estimate_mounting(campaign), "estimated from the data"
    else:
        mounting, source = Rotation.from_quat(declared), "nominal (campaign.yaml)"
        residual, residual_sd = estimate_mounting(aligned(campaign, mounting))
        if residual.magnitude() > physical_limits(campaign.channels)[1]:
            mounting, source, sd_deg = residual * mounting, "nominal, refined by the data's alignment", residual_sd
    applied = {"quat": mounting.as_quat().tolist(), "source": source,
               "angle_deg": float(np.rad2deg(mounting.magnitude()))}
    if sd_deg is not None:
        applied["sd_deg"] = {a: float(v) for a, v in zip(AXES, sd_deg)}
    return aligned(campaign, mounting), applied


