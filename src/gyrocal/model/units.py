"""Unit conversions and axis names. SI radians inside; ppm and arcsec only at the edges."""

import numpy as np

__all__ = [
    "ARCSEC_RAD", "AXES", "AXIS_INDEX", "DEG_H_RAD_S", "DEG_SQRT_H_RAD_SQRT_S", "PAPER_AXES", "PAPER_AXIS_NUMBER", "PPM",
    "STANDARD_GRAVITY_M_S2", "arcsec_to_rad", "arw_to_rad_sqrt_s", "deg_h_to_rad_s", "paper_term", "rad_s_to_deg_h",
    "rad_to_arcsec"
]

ARCSEC_RAD = np.pi / (180.0 * 3600.0)
"""One arcsecond in radians (1 rad = 206264.806 arcsec)."""

PPM = 1e-6
"""One part per million."""

DEG_SQRT_H_RAD_SQRT_S = np.deg2rad(1.0) / 60.0
"""One deg/sqrt(h) of angle random walk in rad/sqrt(s)."""

DEG_H_RAD_S = np.deg2rad(1.0) / 3600.0
"""One deg/h of rate (a gyro bias) in rad/s."""

STANDARD_GRAVITY_M_S2 = 9.80665
"""One g of specific force in m/s^2 (a g-sensitivity in deg/s/g)."""

AXES = ("roll", "pitch", "yaw")
"""Body axes in index order: x = roll, y = pitch, z = yaw (docs/interface.md section 1)."""

AXIS_INDEX = {name: i for i, name in enumerate(AXES)}

PAPER_AXES = ("yaw", "roll", "pitch")
"""The paper's axis order: its tables number the axes 1 = yaw, 2 = roll, 3 = pitch."""

PAPER_AXIS_NUMBER = {name: i + 1 for i, name in enumerate(PAPER_AXES)}


def paper_term(axis: str, toward: str) -> str:
    """The paper's name of a misalignment: ``mc12`` is the yaw channel's toward roll."""
    return f"mc{PAPER_AXIS_NUMBER[axis]}{PAPER_AXIS_NUMBER[toward]}"


def arcsec_to_rad(arcsec):
    return np.asarray(arcsec, dtype=float) * ARCSEC_RAD


def rad_to_arcsec(rad):
    return np.asarray(rad, dtype=float) / ARCSEC_RAD


def arw_to_rad_sqrt_s(arw_deg_sqrt_h):
    return np.asarray(arw_deg_sqrt_h, dtype=float) * DEG_SQRT_H_RAD_SQRT_S


def deg_h_to_rad_s(deg_h):
    return np.deg2rad(np.asarray(deg_h, dtype=float)) / 3600.0


def rad_s_to_deg_h(rad_s):
    return np.rad2deg(np.asarray(rad_s, dtype=float)) * 3600.0
