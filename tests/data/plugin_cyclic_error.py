"""A user's effect in arcsec that is not a gyro-channel term: a cyclic angle error.

Every channel's output carries the same small error periodic in the angle it has turned
through, ``amplitude * sin(angle)``, as a readout with a once-per-turn error would. Its
one parameter shares the channel misalignments' unit but belongs to no channel.
"""

import numpy as np

from gyrocal.model.effects import Effect, Parameter
from gyrocal.model.units import ARCSEC_RAD


class CyclicError(Effect):
    name = "cyclic_error"
    description = "an angle error periodic in each channel's turned angle, the same on every channel"
    parameters = (Parameter("amplitude", "arcsec", ARCSEC_RAD, 30.0, 600.0, per_channel=False),)

    def gyro(self, m):
        """d(amplitude * sin(angle)) per gyro interval: cos(angle) times the channel's increment."""
        angle = np.cumsum(m.increments, axis=0) - 0.5 * m.increments
        return {"amplitude": np.cos(angle) * m.increments}


EFFECTS = [CyclicError()]
