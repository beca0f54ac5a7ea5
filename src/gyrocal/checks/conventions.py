"""Conventions before physics: a campaign-wide fault (conjugated or scalar-first quaternions,
increments in degrees or another unit) shows in every maneuver, and the per-maneuver checks would
name it once per maneuver and channel set, or blame what it upsets downstream. Here each
reading of the files is tried on every maneuver at once; where the files as written fail and
one other reading makes every maneuver consistent (`sensing.consistent`: within the scale and
misalignment bounds the effects declare), one finding names it, with the file and columns."""

import numpy as np

from gyrocal.checks.physics import ALTERNATIVES
from gyrocal.checks.sensing import consistent, consistent_any, interval_rotations, reference_noise_rad, sense
from gyrocal.finding import Findings
from gyrocal.io.telemetry import Campaign, TelemetryError
from gyrocal.maneuvers import preprocess
from gyrocal.model.units import AXIS_INDEX

__all__ = ["QUATERNION_READINGS", "convention_findings"]

QUATERNION_READINGS = (
    ("conjugated (the inverse convention: the inertial frame's attitude in body axes, or a "
     "vector-rotation quaternion)", [0, 1, 2, 3], [-1, -1, -1, 1]),
    ("scalar first (q0, q1, q2, q3)", [1, 2, 3, 0], [1, 1, 1, 1]),
    ("scalar first and conjugated", [1, 2, 3, 0], [-1, -1, -1, 1]),
)
"""Other readings of ``q1..q4``: the cause, the column order that undoes it and the signs."""


def convention_findings(campaign: Campaign, limits, findings: Findings) -> bool:
    """One finding for a campaign-wide convention fault, where one reading other than the files'
    makes every maneuver consistent and the files as written leave one or more inconsistent;
    returns whether it found one."""
    sf_bound, mis_bound, _ = limits
    sensed = []
    for m in campaign.maneuvers:
        try:
            sensed.append(sense(preprocess.slice_maneuver(campaign, m.id)))
        except (TelemetryError, ValueError, IndexError):
            return False  # the per-maneuver checks say what is wrong with it
    if not sensed:
        return False

    def every(gyro_factor=1.0, order=None, signs=None):
        """Each maneuver's consistency under one reading: about its labelled axis, or for free motion
        as the 3x3 response, which must then determine a direction (`sensing.consistent_any`)."""
        results = []
        for s in sensed:
            d_st = s.d_st
            if order is not None:
                d_st = interval_rotations(s.data.st_quat[:, order] * signs)
            if s.data.axis is None:
                results.append(consistent_any(s.d_gyro / gyro_factor, d_st, s.dt, sf_bound, mis_bound,
                                              reference_noise_rad(s), need_determined=order is not None or gyro_factor != 1.0))
            else:
                results.append(consistent(s.d_gyro / gyro_factor, d_st, s.dt, AXIS_INDEX[s.data.axis], sf_bound, mis_bound))
        return results

    def turned(s):
        """The maneuver's most-turned body axis: its label, or for free motion the axis the reference turns most."""
        return AXIS_INDEX[s.data.axis] if s.data.axis is not None else int(np.argmax(np.abs(s.d_st).sum(axis=0)))

    as_written = every()
    if all(as_written):
        return False
    failing = sum(not ok for ok in as_written)
    n = len(sensed)
    lines = campaign.lines
    st_lines = f"lines {lines['star_tracker.csv'][0]}-{lines['star_tracker.csv'][-1]}"
    for cause, order, signs in QUATERNION_READINGS:
        if all(every(order=order, signs=np.array(signs, dtype=float))):
            findings.refuse(
                "conventions",
                f"star_tracker.csv, columns q1..q4, {st_lines}: the quaternions look {cause}: read so, every "
                f"maneuver's rotation matches the gyros' ({n} of {n}); as written, {failing} of {n} do not. The "
                "contract's q1..q4 are the body's attitude in the inertial frame, scalar last (docs/interface.md "
                "section 1): write them so", where="star_tracker.csv:q1..q4")
            return True
    dt_gyro = float(np.median(np.diff(campaign.gyro_time)))
    factors = list(ALTERNATIVES) + [
        (1.0 / dt_gyro, f"rates in rad/s rather than increments ({1 / dt_gyro:.4g} Hz is the gyro's sample rate)"),
        (180.0 / np.pi / dt_gyro, "rates in deg/s rather than increments in rad")]
    g_lines = f"lines {lines['gyro.csv'][0]}-{lines['gyro.csv'][-1]}"
    for factor, cause in factors:
        if all(every(gyro_factor=factor)):
            scale = np.median([np.ptp(np.cumsum(s.d_gyro[:, turned(s)])) / np.ptp(np.cumsum(s.d_st[:, turned(s)]))
                               for s in sensed])
            findings.refuse(
                "conventions",
                f"gyro.csv, columns {', '.join(campaign.channel_names)}, {g_lines}: every maneuver's gyro rotation is "
                f"{scale:.4g} times the star tracker's ({n} of {n}; divided by {factor:.4g} every one matches): "
                f"{cause.rstrip('?')}? The contract's increments are in rad, the angle since the previous row "
                "(docs/interface.md section 3)", where="gyro.csv")
            return True
    return False
