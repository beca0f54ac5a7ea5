"""A user's effect, in a plugin file: a rate fixed in the room, sensed by the gyros and not by a
reference fixed to the room.

Found by the model-criticism loop on the RepoIMU trials (docs/real-data.md, step 12). The gyros
measure the rate against inertial space; motion capture measures the attitude against the room,
which turns with the Earth (15.04 deg/h; at 50.3 deg N, 11.6 of it up and 9.6 north), and a gyro
sensitive to the magnetic field senses a rate along the room's field too. Either is a constant
vector in the room; seen from a body that turns, it is not the constant bias the gyro model
already has. The room's axes in body coordinates come from the specific force (up, where the
motion's own acceleration is small against gravity) and the magnetic field's part across it
(magnetic north): the ``gyro.csv`` columns ``acc_x``, ``acc_y``, ``acc_z`` and ``mag_x``,
``mag_y``, ``mag_z``, which `gyrocal import repoimu` keeps.
"""

import numpy as np

from gyrocal.errors import InputError
from gyrocal.model.effects import Effect, Parameter

DEG_PER_HOUR_RAD_S = np.pi / 180.0 / 3600.0
ROOM_AXES = ("up", "north", "west")


def room_axes(extras) -> np.ndarray:
    """(K, 3, 3): the room's up, magnetic north and west as unit vectors in body axes, per gyro
    interval, from the specific force and the magnetic field (``extras``: the gyro.csv columns)."""
    acc = np.column_stack([extras[f"acc_{a}"] for a in "xyz"])
    mag = np.column_stack([extras[f"mag_{a}"] for a in "xyz"])
    acc_norm = np.linalg.norm(acc, axis=1, keepdims=True)
    if not np.all(acc_norm > 0):
        raise InputError("effect lab_rate: the specific force (acc_x, acc_y, acc_z) is zero on some rows, so "
                         "the room's vertical is unknown there")
    up = acc / acc_norm
    north = mag - np.sum(mag * up, axis=1, keepdims=True) * up
    north_norm = np.linalg.norm(north, axis=1, keepdims=True)
    if not np.all(north_norm > 0):
        raise InputError("effect lab_rate: the magnetic field (mag_x, mag_y, mag_z) has no horizontal part on "
                         "some rows, so the room's north is unknown there")
    north = north / north_norm
    return np.stack([up, north, np.cross(up, north)], axis=1)


class LabRate(Effect):
    name = "lab_rate"
    description = ("a rate fixed in the room (the Earth's rotation, a magnetic sensitivity), sensed by the gyros and "
                   "not by a reference fixed to the room; the room's axes from gyro.csv's acc_* and mag_* columns")
    parameters = tuple(Parameter(f"rate_{axis}", "deg/h", DEG_PER_HOUR_RAD_S, 100.0, 3600.0, per_channel=False)
                       for axis in ROOM_AXES)

    def gyro(self, m):
        """Each channel senses the room's rate along its own axis: its increment changes by the
        rate's body component on that axis times the interval."""
        axes = room_axes(m.extras)
        index = [c.axis_index for c in m.channels]
        return {p.name: axes[:, k, index] * m.dt[:, None] for k, p in enumerate(self.parameters)}


EFFECTS = [LabRate()]
