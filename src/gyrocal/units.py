"""Unit conversions and axis names. SI radians inside; ppm and arcsec only at the edges."""

import numpy as np

ARCSEC_RAD = np.pi / (180.0 * 3600.0)
"""One arcsecond in radians (1 rad = 206264.806 arcsec)."""

PPM = 1e-6
"""One part per million."""

DEG_SQRT_H_RAD_SQRT_S = np.deg2rad(1.0) / 60.0
"""One deg/sqrt(h) of angle random walk in rad/sqrt(s)."""

AXES = ("roll", "pitch", "yaw")
"""Body axes in index order: x = roll, y = pitch, z = yaw (interface.md section 1)."""

AXIS_INDEX = {name: i for i, name in enumerate(AXES)}

PAPER_AXIS_NUMBER = {"yaw": 1, "roll": 2, "pitch": 3}
"""The paper's tables index axes 1 = yaw, 2 = roll, 3 = pitch."""


def arcsec_to_rad(arcsec):
    return np.asarray(arcsec, dtype=float) * ARCSEC_RAD


def rad_to_arcsec(rad):
    return np.asarray(rad, dtype=float) / ARCSEC_RAD


def arw_to_rad_sqrt_s(arw_deg_sqrt_h):
    return np.asarray(arw_deg_sqrt_h, dtype=float) * DEG_SQRT_H_RAD_SQRT_S
