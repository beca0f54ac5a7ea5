import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from gyrocal.model import kinematics
from gyrocal.model.units import ARCSEC_RAD


def test_compose_matches_scipy_rotation_product():
    a = Rotation.random(50, random_state=1)
    b = Rotation.random(50, random_state=2)
    ours = kinematics.compose(a, b)
    assert np.allclose((ours.inv() * (a * b)).magnitude(), 0, atol=1e-14)


def test_constant_rate_about_yaw_matches_closed_form():
    rate, dt, n = np.deg2rad(0.5), 0.1, 1800          # 90 deg in 180 s
    inc = np.tile([0.0, 0.0, rate * dt], (n, 1))
    start = Rotation.random(random_state=3)
    att = kinematics.propagate(start, inc)
    expected = start * Rotation.from_rotvec([0, 0, rate * dt * n])
    assert len(att) == n + 1
    assert (att[-1].inv() * expected).magnitude() < 1e-12


def test_propagation_is_exact_for_constant_rate_on_any_axis_not_first_order():
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    rate, dt, n = 0.02, 0.5, 400                       # big steps: Euler would drift
    att = kinematics.propagate(Rotation.identity(), np.tile(axis * rate * dt, (n, 1)))
    for k in (1, 37, 400):
        closed = Rotation.from_rotvec(axis * rate * dt * k)
        assert (att[k].inv() * closed).magnitude() < 1e-12


def test_propagation_matches_sequential_composition_for_varying_rates():
    inc = np.random.default_rng(0).normal(0, 1e-3, (1000, 3))
    att = kinematics.propagate(Rotation.identity(), inc)
    seq = Rotation.identity()
    for d in inc:
        seq = seq * Rotation.from_rotvec(d)
    assert (att[-1].inv() * seq).magnitude() < 1e-13



def test_propagation_in_blocks_gives_the_same_bits_as_in_one_block(monkeypatch):
    """The scan runs in place block by block to bound memory: the block size changes no number."""
    inc = np.random.default_rng(1).normal(0, 1e-3, (1000, 3))
    start = Rotation.random(random_state=4)
    whole = kinematics.propagate(start, inc).as_quat()
    scan = kinematics.cumulative_compose(Rotation.from_rotvec(inc)).as_quat()
    monkeypatch.setattr(kinematics, "_CHUNK", 7)
    assert np.array_equal(kinematics.propagate(start, inc).as_quat(), whole)
    assert np.array_equal(kinematics.cumulative_compose(Rotation.from_rotvec(inc)).as_quat(), scan)
    seq = Rotation.identity()
    for d in inc[:300]:
        seq = seq * Rotation.from_rotvec(d)
    assert (Rotation.from_quat(scan[299]).inv() * seq).magnitude() < 1e-13

def test_body_rate_convention_matches_the_paper_eq_1_2():
    """dq/dt = 1/2 Omega(omega) q with the paper's Omega, scalar-last q."""
    w = np.array([0.01, -0.02, 0.03])
    q = Rotation.random(random_state=5).as_quat()
    wx, wy, wz = w
    omega = np.array([[0, wz, -wy, wx], [-wz, 0, wx, wy], [wy, -wx, 0, wz], [-wx, -wy, -wz, 0]])
    dt = 1e-6
    q_next = kinematics.propagate(Rotation.from_quat(q), [w * dt])[-1].as_quat()
    q_next *= np.sign(q_next @ q)
    assert np.allclose((q_next - q) / dt, 0.5 * omega @ q, atol=1e-8)


def test_attitude_at_interpolates_exactly_within_a_constant_rate_sample():
    times = np.array([0.0, 1.0, 2.0])
    inc = np.array([[0, 0, 0.01], [0.02, 0, 0]])
    att = kinematics.propagate(Rotation.identity(), inc)
    mid = kinematics.attitude_at(times, att, inc, [1.25])
    expected = Rotation.from_rotvec([0, 0, 0.01]) * Rotation.from_rotvec([0.005, 0, 0])
    assert (mid[0].inv() * expected).magnitude() < 1e-14
    with pytest.raises(ValueError, match="outside"):
        kinematics.attitude_at(times, att, inc, [2.5])


def test_error_angles_give_star_tracker_relative_to_gyro_in_body_axes():
    gyro = Rotation.random(random_state=4)
    truth = gyro * Rotation.from_rotvec([10 * ARCSEC_RAD, -20 * ARCSEC_RAD, 30 * ARCSEC_RAD])
    err = kinematics.error_angles_arcsec(Rotation.concatenate([gyro]), Rotation.concatenate([truth]))
    assert np.allclose(err, [[10, -20, 30]], atol=1e-9)


def test_quaternion_sign_flips_change_no_error_angle_and_no_interpolated_attitude():
    """q and -q are one attitude: the star tracker's quaternions need no sign-continuity pass."""
    q = Rotation.from_rotvec(np.outer(np.linspace(0, 1, 20), [0.2, 0.1, 1.0])).as_quat()
    flipped = q * np.where(np.arange(20) % 3 == 0, -1, 1)[:, None]
    model = Rotation.from_rotvec(np.random.default_rng(4).normal(0, 1e-4, (20, 3))) * Rotation.from_quat(q)
    assert np.array_equal(kinematics.error_angles_rad(model, Rotation.from_quat(q)),
                          kinematics.error_angles_rad(model, Rotation.from_quat(flipped)))
    t = np.arange(20.0)
    a = Slerp(t, Rotation.from_quat(q))([3.5, 9.25, 17.0]).as_matrix()
    b = Slerp(t, Rotation.from_quat(flipped))([3.5, 9.25, 17.0]).as_matrix()
    assert np.abs(a - b).max() < 1e-15
