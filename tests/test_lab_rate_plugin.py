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


def test_the_earths_rate_sensed_by_the_gyros_is_recovered_with_its_sign_through_gyrocals_error_model():
    """End to end, through `errormodel.linearize`: a body tumbling in a room at 50.3 deg N whose gyros
    sense the Earth's rate (15.041 deg/h: 11.57 up, 9.61 north, 0 west) besides the room-relative
    rate; a least-squares fit of the plugin's columns, the biases and the initial error to the
    attitude error gives the Earth's rate back, signs included (found by an independent review)."""
    from gyrocal.inference.errormodel import linearize
    from gyrocal.maneuvers.preprocess import ManeuverData
    from gyrocal.model.effects import LIBRARY
    from gyrocal.model.spec import ModelSpec

    latitude = np.radians(50.3)
    earth_room = 15.041 * RAD_PER_DEG_H * np.array([np.cos(latitude), 0.0, np.sin(latitude)])  # north, west, up
    plugin = load_plugins([PLUGIN])["lab_rate"]
    channels = (Channel("gyro_x", None, "roll"), Channel("gyro_y", None, "pitch"), Channel("gyro_z", None, "yaw"))
    spec = ModelSpec.build("t", [LIBRARY["scale_factor"], LIBRARY["misalignment"], LIBRARY["bias"], plugin], channels)
    euler = lambda t: np.column_stack([1.0 * t, 0.6 * np.sin(0.3 * t), 0.5 * np.cos(0.17 * t)])
    dt, t = 0.01, np.arange(0.0, 90.0 + 0.005, 0.01)
    attitude = Rotation.from_euler("zyx", euler(t))
    mid = Rotation.from_euler("zyx", euler(0.5 * (t[1:] + t[:-1])))
    increments = (attitude[:-1].inv() * attitude[1:]).as_rotvec() + mid.inv().apply(earth_room) * dt
    dip = np.radians(66.0)
    force, field = mid.inv().apply([0.0, 0.0, 9.81]), mid.inv().apply([np.cos(dip), 0.0, -np.sin(dip)])
    extras = {f"acc_{a}": force[:, i] for i, a in enumerate("xyz")}
    extras.update({f"mag_{a}": field[:, i] for i, a in enumerate("xyz")})
    data = ManeuverData("m", "yaw", "both", channels, (), t, increments, t[100::100], attitude[100::100].as_quat(),
                        attitude[0].as_quat(), extras)
    lin = linearize(data, spec, np.zeros(len(spec)), np.zeros(3))
    rate = [j for j, p in enumerate(spec.parameters) if p.effect == "lab_rate"]
    columns = [lin.design[:, 0, :, j] for j in rate] + [lin.bias_design[:, 0, :, j] for j in range(3)]
    columns += [np.tile(np.eye(3)[i], (len(lin.z), 1)) for i in range(3)]
    fitted, *_ = np.linalg.lstsq(np.stack([c.reshape(-1) for c in columns], 1), lin.z[:, 0].reshape(-1), rcond=None)
    np.testing.assert_allclose(fitted[:3] / RAD_PER_DEG_H, [11.573, 9.608, 0.0], atol=0.01)
