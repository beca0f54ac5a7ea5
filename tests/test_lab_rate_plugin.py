"""The RepoIMU example plugin (``docs/real-data/plugin_lab_rate.py``): a rate fixed in the room, seen
from a body that turns, against the increments it adds, computed directly."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gyrocal.errors import InputError
from gyrocal.model.channels import Channel
from gyrocal.model.effects import load_plugins

PLUGIN = Path(__file__).resolve().parents[1] / "docs" / "real-data" / "plugin_lab_rate.py"
RAD_PER_DEG_H = np.pi / 180 / 3600


def _yawing_and_tilting(k=400, dt=0.01):
    """A body turning about changing axes in a room whose up is z and magnetic north is x (the field
    dipping 60 deg), sensed with a little linear acceleration on top of gravity."""
    t = np.arange(k) * dt
    body_to_room = Rotation.from_euler("zyx", np.column_stack([2.0 * t, 0.3 * np.sin(t), 0.2 * np.cos(3 * t)]))
    gravity_up = body_to_room.inv().apply([0.0, 0.0, 9.81])
    field = body_to_room.inv().apply([np.cos(np.radians(60)), 0.0, -np.sin(np.radians(60))])
    wobble = np.random.default_rng(0).normal(scale=0.05, size=(k, 3))
    extras = {f"acc_{a}": gravity_up[:, i] + wobble[:, i] for i, a in enumerate("xyz")}
    extras.update({f"mag_{a}": field[:, i] for i, a in enumerate("xyz")})
    return body_to_room, extras, np.full(k, dt)


def test_the_plugin_loads_through_gyrocals_plugin_api():
    effect = load_plugins([PLUGIN])["lab_rate"]
    assert [p.name for p in effect.parameters] == ["rate_up", "rate_north", "rate_west"]
    assert effect.parameters[0].si_per_unit == pytest.approx(RAD_PER_DEG_H)


def test_a_room_fixed_rate_adds_its_body_component_along_each_channel():
    """A rate of (11.6 up, 9.6 north, -5 west) deg/h fixed in the room adds, to each channel of a
    turning body, its component on the channel's axis times dt: the plugin's columns times the rate
    give it exactly where the accelerometer senses gravity alone, and to 5 % of the rate with a
    wobble of 0.05 m/s^2 per axis on top."""
    effect = load_plugins([PLUGIN])["lab_rate"]
    body_to_room, extras, dt = _yawing_and_tilting()
    rate_room = np.array([9.6, 5.0, 11.6]) * RAD_PER_DEG_H  # x north, y west, z up
    added = body_to_room.inv().apply(rate_room) * dt[:, None]
    channels = [Channel("gyro_z", None, "yaw"), Channel("gyro_x", None, "roll"), Channel("gyro_y", None, "pitch")]
    columns = effect.gyro(SimpleNamespace(extras=extras, dt=dt, channels=channels))
    predicted = sum(columns[f"rate_{axis}"] * value for axis, value in zip(("up", "north", "west"), (11.6, 9.6, 5.0)))
    np.testing.assert_allclose(predicted * RAD_PER_DEG_H, added[:, [2, 0, 1]], atol=0.05 * np.abs(added).max())
    still = _yawing_and_tilting()[1]
    still.update({f"acc_{a}": v for a, v in zip("xyz", body_to_room.inv().apply([0.0, 0.0, 9.81]).T)})
    exact = effect.gyro(SimpleNamespace(extras=still, dt=dt, channels=channels))
    exact_sum = sum(exact[f"rate_{axis}"] * value for axis, value in zip(("up", "north", "west"), (11.6, 9.6, 5.0)))
    np.testing.assert_allclose(exact_sum * RAD_PER_DEG_H, added[:, [2, 0, 1]], rtol=1e-9, atol=1e-18)


def test_a_field_along_the_vertical_is_refused_with_the_reason():
    effect = load_plugins([PLUGIN])["lab_rate"]
    extras = {f"acc_{a}": np.array([0.0, 0.0, 9.81])[i] * np.ones(3) for i, a in enumerate("xyz")}
    extras.update({f"mag_{a}": np.array([0.0, 0.0, 1.0])[i] * np.ones(3) for i, a in enumerate("xyz")})
    with pytest.raises(InputError, match="no horizontal part"):
        effect.gyro(SimpleNamespace(extras=extras, dt=np.ones(3), channels=[Channel("gyro_z", None, "yaw")]))
