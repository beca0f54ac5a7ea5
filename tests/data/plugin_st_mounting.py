"""A user's effect in arcsec that is not a gyro-channel term: the star tracker's mounting.

The star tracker's frame is turned from the body frame by small fixed angles about roll
and pitch, so its measured attitude carries a constant error in body axes. Its
parameters share the channel misalignments' unit but belong to no channel.
"""

import numpy as np

from gyrocal.effects import Effect, Parameter
from gyrocal.units import ARCSEC_RAD


class StMounting(Effect):
    name = "st_mounting"
    description = "the star tracker's mounting turned from the body frame about roll and pitch"
    parameters = (Parameter("mount_roll", "arcsec", ARCSEC_RAD, 30.0, 600.0, per_channel=False),
                  Parameter("mount_pitch", "arcsec", ARCSEC_RAD, 30.0, 600.0, per_channel=False))

    def star_tracker(self, m):
        ones = np.ones(len(m.st_time))
        zeros = np.zeros(len(m.st_time))
        return {"mount_roll": np.column_stack([ones, zeros, zeros]),
                "mount_pitch": np.column_stack([zeros, ones, zeros])}


EFFECTS = [StMounting()]
