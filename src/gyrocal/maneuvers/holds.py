"""The inertial holds around a single-axis rotation: where the maneuver's axis is still.

The paper's method (`gyrocal.inference.fit.classic`) averages the error held before and after
each rotation; the verdict and the checks read the same windows.
"""

import numpy as np

from gyrocal.maneuvers.preprocess import ManeuverData, body_increments
from gyrocal.model import channels as ch
from gyrocal.model.channels import MOVING_RATE_FRACTION
from gyrocal.model.units import AXIS_INDEX

__all__ = ["MIN_HOLD_SAMPLES", "hold_windows", "missing_holds"]

MIN_HOLD_SAMPLES = 3
"""Star-tracker samples a hold needs for the classic method to average over it."""


def hold_windows(data: ManeuverData, channel_set=None):
    """Star-tracker masks of the inertial holds before and after the rotation: where the
    maneuver-axis rate (for free motion, the rate's magnitude) is below `MOVING_RATE_FRACTION` of its peak."""
    channel_set = channel_set or data.sets[0]
    inc = body_increments(data, channel_set, ch.ChannelParams.zeros(data.channels))
    turned = np.linalg.norm(inc, axis=1) if data.axis is None else inc[:, AXIS_INDEX[data.axis]]
    rate = np.abs(turned / data.dt)
    moving = np.flatnonzero(rate > MOVING_RATE_FRACTION * rate.max())
    t_first, t_last = data.gyro_time[moving[0]], data.gyro_time[moving[-1] + 1]
    return data.st_time < t_first, data.st_time > t_last


def missing_holds(data: ManeuverData) -> list:
    """Which holds (``"before"``, ``"after"``) a maneuver lacks for the classic method."""
    before, after = hold_windows(data)
    return [name for name, mask in (("before", before), ("after", after)) if mask.sum() < MIN_HOLD_SAMPLES]
