"""A campaign's maneuvers made ready for any fit: sliced, the gyro attitude propagated from the
reference, the error angles of eq. 4, and the inertial holds around each rotation."""

from gyrocal.maneuvers.holds import hold_windows, missing_holds
from gyrocal.maneuvers.preprocess import ManeuverData, error_angles, noise_groups, slice_maneuver

__all__ = ["ManeuverData", "error_angles", "hold_windows", "missing_holds", "noise_groups", "slice_maneuver"]
