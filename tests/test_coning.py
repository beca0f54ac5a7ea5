"""The gyro's rotation between reference samples, for checks that hold it against the reference's:
its increments composed, not summed, whose difference (the coning error) grows as the square of the
turn per interval where the axis moves."""

import numpy as np
from scipy.spatial.transform import Rotation

from gyrocal.checks import sensing
from gyrocal.maneuvers.preprocess import ManeuverData
from gyrocal.model.channels import Channel

STEP_S, EVERY = 0.0035, 29
"""BROAD's gyro step, and its reference kept every 29th sample (0.1 s)."""


def coning_maneuver(every=EVERY, intervals=40, spin_rad_s=1.0):
    """A hand-held-like tumble: 3 rad/s about an axis that circles the z axis once a second,
    ``spin_rad_s`` about z; the reference is the exact composition of the gyro's increments, every
    ``every``-th sample, over ``intervals`` of them."""
    channels = tuple(Channel(f"gyro_{a}", None, axis) for a, axis in zip("xyz", ("roll", "pitch", "yaw")))
    time = np.arange(0, every * intervals + 1) * STEP_S
    mid = 0.5 * (time[1:] + time[:-1])
    rate = np.column_stack([3 * np.cos(2 * np.pi * mid), 3 * np.sin(2 * np.pi * mid), np.full_like(mid, spin_rad_s)])
    increments = rate * STEP_S
    attitude = [Rotation.identity()]
    for inc in increments:
        attitude.append(attitude[-1] * Rotation.from_rotvec(inc))
    kept = np.arange(0, len(time), every)
    st_quat = np.array([attitude[k].as_quat() for k in kept])
    return ManeuverData("tumble", None, None, channels, tuple(c.name for c in channels), time, increments,
                        time[kept], st_quat, attitude[0].as_quat())


def test_the_composed_gyro_rotation_between_reference_samples_is_the_references_and_the_sum_is_not():
    sensed = sensing.sense(coning_maneuver())
    turn = np.linalg.norm(sensed.d_st, axis=1)
    assert np.max(np.abs(sensed.d_gyro_turned - sensed.d_st)) < 1e-9 * np.max(turn)
    coning = np.linalg.norm(sensed.d_gyro - sensed.d_st, axis=1) / turn
    assert np.median(coning) > 0.01   # a percent of the turn and more: beyond what a check may allow a DTG


def test_the_free_motion_check_accepts_the_tumble_its_summed_increments_put_off():
    sensed = sensing.sense(coning_maneuver(intervals=80))  # 8 blocks: 4 would leave the fit no residual
    sf_bound, mis_bound, _ = sensing.physical_limits(sensed.data.channels, "dtg")
    assert sensing.consistent_any(sensed.d_gyro_turned, sensed.d_st, sensed.dt, sf_bound, mis_bound, 1e-6)
    assert not sensing.consistent_any(sensed.d_gyro, sensed.d_st, sensed.dt, sf_bound, mis_bound, 1e-6)


def test_intervals_the_gyro_turns_more_than_a_quarter_turn_in_are_left_out_of_the_comparison():
    d_gyro = np.array([[0.1, 0, 0], [np.deg2rad(120), 0, 0], [0, np.deg2rad(89), 0]])
    assert sensing.comparable(d_gyro).tolist() == [True, False, True]


def test_a_maneuver_that_only_shakes_does_not_have_its_clocks_refused_on_a_shift_its_noise_picks():
    """Gyro and reference each see only their own noise (no motion to line up): the best shift of the
    clock search is the noise's, seconds off, and lowers the misfit by little: a warning at most, never
    the refusal a real offset of seconds gets."""
    from gyrocal.checks.sampling import clock_findings, clock_search
    from gyrocal.finding import Findings

    rng = np.random.default_rng(11)
    channels = tuple(Channel(f"gyro_{a}", None, axis) for a, axis in zip("xyz", ("roll", "pitch", "yaw")))
    time = np.arange(4001) * 0.01
    increments = 1e-5 * rng.standard_normal((4000, 3))
    kept = np.arange(0, 4001, 10)
    st_quat = Rotation.from_rotvec(2e-5 * rng.standard_normal((len(kept), 3))).as_quat()
    data = ManeuverData("shake", None, None, channels, tuple(c.name for c in channels), time, increments, time[kept],
                        st_quat, st_quat[0])
    sensed = sensing.sense(data)
    offset, gain, left = clock_search(sensed)
    findings = Findings()
    clock_findings(sensed, findings)
    assert not findings.errors
    if abs(offset) > 0.2:
        assert any("the clocks are not checked on it" in w for w in findings.warnings)
    assert gain / (left / (3 * len(kept))) < 25.0


def test_a_wobble_within_a_sparse_references_interval_is_not_taken_for_a_unit_slip():
    """The reference every second (286 samples) on the tumble with a slow spin: the sums of increments
    per interval are a third of the turn (the axis circles within it), so the gyros' path over the
    reference's is far below one; the composed rotations fit, with a direction determined, and that
    positive evidence stands (the path ratio is asked only where there is none)."""
    from types import SimpleNamespace

    from gyrocal.checks import physics
    from gyrocal.finding import Findings

    data = coning_maneuver(every=286, intervals=60, spin_rad_s=0.3)
    sensed = sensing.sense(data)
    assert physics.path_ratio(sensed) < physics.GROSS_SCALE[0]
    maneuver = SimpleNamespace(id=data.id, free=True, t_start=float(data.gyro_time[0]), t_end=float(data.gyro_time[-1]))
    campaign = SimpleNamespace(maneuver=lambda _: maneuver)
    findings = Findings()
    limits = sensing.physical_limits(data.channels, "mems")
    assert physics.rotation_findings(campaign, sensed, limits, findings) and not findings.errors


def test_intervals_spanning_less_than_a_block_are_summed_as_one_block():
    """A reading under which the gyro turns too far to compare in most intervals can leave two short
    ones, under one `CHECK_BLOCK_S` together: they are one block, not none (which ended RepoIMU's
    Test05 Trial3 at 1 s in a numpy error rather than its clipping refusal)."""
    blocked_dt, blocked_d = sensing.blocked_sums(np.array([0.3, 0.4]), np.array([[1.0, 0.0, 0.0], [2.0, 1.0, 0.0]]))
    np.testing.assert_allclose(blocked_dt, [0.7])
    np.testing.assert_allclose(blocked_d, [[3.0, 1.0, 0.0]])
    np.testing.assert_allclose(sensing.blocked_sums(np.full(6, 0.5), np.arange(6.0))[1], [1.0, 5.0, 9.0])


def test_a_fit_with_no_residual_left_determines_nothing():
    """Three blocks in which the gyros turn exactly as the reference: the fit of three axes and a rate
    matches them exactly, with nothing left to measure the noise by, so it is not evidence either way
    (it used to count as consistent, to a sd of 1e-15). With a fourth, fifth and sixth it is."""
    rng = np.random.default_rng(2)
    d = rng.normal(0, 0.1, (6, 3)) + [0.5, 0.0, 0.0]
    d_gyro = d + rng.normal(0, 1e-6, d.shape)
    dt = np.ones(6)
    assert not sensing.consistent(d[:3], d[:3], dt[:3], 0, 0.02, 0.01)
    assert sensing.response(d[:4], d[:4], dt[:4], 0.02).short
    assert sensing.consistent(d_gyro, d, dt, 0, 0.02, 0.01)
