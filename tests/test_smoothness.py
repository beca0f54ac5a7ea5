"""The residual's increment growth (`gyrocal.inference.noise.smoothness`) on series whose variogram is known."""

from pathlib import Path

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from gyrocal.criticism.increments import smoothness_finding
from gyrocal.inference.fit.noisefit import GM_LOGIT_BOUND
from gyrocal.inference.noise import smoothness
from gyrocal.inference.sampling.refusals import share_at_bound

ROOT = Path(__file__).resolve().parents[1]


def _measured(residual, interval_s=0.01, name="m"):
    lags, exponent, se = smoothness.growth(residual)
    return smoothness.Smoothness(name, interval_s, lags, exponent, se)


def _gauss_markov(rng, m, phi):
    g = np.zeros((m, 3))
    e = rng.normal(size=(m, 3)) * np.sqrt(1 - phi**2)
    g[0] = rng.normal(size=3)
    for j in range(1, m):
        g[j] = phi * g[j - 1] + e[j]
    return g


def test_white_noise_does_not_grow_and_a_random_walk_grows_as_the_square_root_of_the_lag():
    rng = np.random.default_rng(0)
    white = _measured(rng.normal(size=(20_000, 3)))
    walk = _measured(np.cumsum(rng.normal(size=(20_000, 3)), axis=0))
    np.testing.assert_allclose(white.exponent[:6], 0.0, atol=0.03)
    assert np.all(np.abs(walk.exponent[:6] - 0.5) < 4 * walk.se[:6]), walk.exponent
    assert not white.smooth and not walk.smooth and white.knee_s == walk.knee_s == 0.0


def test_a_sum_of_white_walk_and_gauss_markov_noise_is_never_beyond_the_models_reach():
    """The model's own noise: 1 s samples, tau 5 s, every part comparable."""
    rng = np.random.default_rng(1)
    m = 5_000
    series = (rng.normal(size=(m, 3)) + 0.3 * np.cumsum(rng.normal(size=(m, 3)), axis=0)
              + 2.0 * _gauss_markov(rng, m, np.exp(-1 / 5.0)))
    s = _measured(series, 1.0)
    assert not s.beyond.any(), s.exponent
    assert smoothness.describe([s]) == "" and smoothness.recommended_interval_s([s]) == 0.0


def _at_truth(seed=1, **changes):
    """Each maneuver's `smoothness.of_maneuver` on a simulated default campaign (``changes``: scenario
    keys, ``section__key``), linearised at the true parameters and weighed at the true ARW: the
    model's own noise, which must never be called smooth."""
    import copy

    from gyrocal.inference import errormodel
    from gyrocal.io.scenario import load_scenario
    from gyrocal.maneuvers import preprocess
    from gyrocal.model.spec import baseline
    from gyrocal.model.units import deg_h_to_rad_s
    from gyrocal.simulation.simulate import simulate

    scenario = copy.deepcopy(load_scenario(ROOT / "config" / "scenarios" / "mom.yaml"))
    for key, value in changes.items():
        section, name = key.split("__")
        (scenario if section == "top" else scenario[section])[name] = value
    campaign, truth = simulate(scenario, seed)
    spec = baseline(campaign.channels)
    theta = spec.core_vector(spec.params_from_contract(scenario["truth"]))
    biases = deg_h_to_rad_s(np.array([truth["parameters"][c.name]["bias_deg_h"] for c in spec.channels]))
    walk = (np.radians(scenario["gyro"]["arw_deg_sqrt_h"]) / 60.0) ** 2
    return [smoothness.of_maneuver(errormodel.linearize(preprocess.slice_maneuver(campaign, m.id), spec, theta,
                                                        biases), walk) for m in campaign.maneuvers]


def test_a_walk_fixed_inertially_seen_from_a_fast_slew_is_not_called_smooth():
    """A large walk (0.3 deg/sqrt(h)) turning at 3 deg/s through four revolutions, seen every 2 s by a
    2-arcsec tracker, grows as lag^1 in the tracker's frame (0.63-0.87 there, 5 of 6 maneuvers called
    smooth before); in the inertial frame, where it is fixed, as lag^0.5."""
    measured = _at_truth(top__star_tracker_hz=0.5, maneuver_defaults__rate_deg_s=3.0,
                         maneuver_defaults__accel_deg_s2=0.5, maneuver_defaults__angle_deg=1440.0,
                         gyro__arw_deg_sqrt_h=0.3, star_tracker__sigma_cross_arcsec=2.0,
                         star_tracker__sigma_about_arcsec=2.0, maneuver_defaults__hold_s=100.0)
    assert not any(s.smooth for s in measured), [s.exponent[0] for s in measured]


@pytest.mark.parametrize("st_hz", [20.0, 7.0])
def test_the_walk_interpolated_between_gyro_samples_is_not_called_smooth(st_hz):
    """A 0.05-arcsec reference off the 10 Hz gyro grid sees the walk interpolated inside gyro intervals,
    short of the lag by a third of an interval: convex, 0.76 at 20 Hz before its shortfall was added
    back (6 of 6 called smooth), 0.49 with it."""
    measured = _at_truth(top__star_tracker_hz=st_hz, star_tracker__sigma_cross_arcsec=0.05,
                         star_tracker__sigma_about_arcsec=0.05, gyro__arw_deg_sqrt_h=0.03, gyro__pulse_arcsec=0.0,
                         maneuver_defaults__hold_s=100.0)
    assert not any(s.smooth for s in measured), [s.exponent[0] for s in measured]
    assert all(abs(s.exponent[0] - 0.5) < 4 * s.se[0] for s in measured)


def test_the_walks_shortfall_is_a_quarter_interval_for_samples_halfway_between_every_other():
    """A reference at 20 Hz on gyros at 10 Hz: every other sample is halfway into a gyro interval, whose
    interpolated walk has ``dt f (1 - f)`` = 0.025 s less variance there; each lag's pairs have one such
    end on average, so the shortfall is 0.025 s at every lag."""
    from gyrocal.inference.errormodel import walk_steps

    gyro_time = np.arange(0.0, 20.0 + 1e-9, 0.1)
    st_time = np.arange(0.05, 19.9, 0.05)
    walk_var, walk_lag1 = walk_steps(gyro_time, st_time)
    st_dt = np.diff(np.concatenate([[gyro_time[0]], st_time]))
    shortfall = smoothness.walk_shortfall(st_dt, walk_var, np.concatenate([[0.0], walk_lag1]), [1, 2, 3, 8])
    np.testing.assert_allclose(shortfall, 0.025, rtol=0.01)
    np.testing.assert_allclose(smoothness.walk_shortfall(np.full(50, 0.1), None, None, [1, 4]), 0.0)


def test_smoothed_noise_is_smooth_up_to_its_kernel_and_the_interval_is_five_knees():
    """White noise through a Gaussian kernel of 8 samples (0.08 s at 100 Hz) is differentiable: its
    increments grow in proportion to the lag below the kernel's width, and no faster beyond it."""
    rng = np.random.default_rng(3)
    s = _measured(gaussian_filter1d(rng.normal(size=(20_000, 3)), 8.0, axis=0), 0.01)
    assert s.smooth and s.exponent[0] > 0.95
    assert 0.04 <= s.knee_s <= 0.32
    interval = smoothness.recommended_interval_s([s])
    assert interval == pytest.approx({0.04: 0.2, 0.08: 0.5, 0.16: 1.0, 0.32: 2.0}[round(s.knee_s, 2)])
    words = smoothness.describe([s, _measured(rng.normal(size=(2_000, 3)), 0.01, "quiet")])
    assert "smooth at the sampling interval on m:" in words and "quiet" not in words
    assert f"reference_interval_s={interval:.3g}" in words and f"--reference-interval {interval:.3g}" in words


@pytest.mark.parametrize(("knee_samples", "expected_s"), [(4, 0.2), (8, 0.5), (16, 1.0), (32, 2.0), (64, 5.0)])
def test_the_recommended_interval_is_five_knees_rounded_up_to_1_2_5(knee_samples, expected_s):
    """A knee at k samples of 10 ms: 5 k x 10 ms, rounded up to 1, 2 or 5 times a power of ten."""
    lags = 2 ** np.arange(8)
    beyond_until = np.log2(knee_samples) - 1
    exponent = np.where(np.arange(8) <= beyond_until, 1.0, 0.3)
    s = smoothness.Smoothness("m", 0.01, lags, exponent, np.full(8, 0.01))
    assert s.knee_s == pytest.approx(knee_samples * 0.01)
    assert smoothness.recommended_interval_s([s]) == pytest.approx(expected_s)


def test_growth_beyond_the_model_at_long_lags_only_is_not_smoothness():
    """A slow structure (the z trial's at 1 s) that grows fast at a long lag does not make the
    residual smooth at the sampling interval, nor set a knee."""
    lags = 2 ** np.arange(5)
    s = smoothness.Smoothness("m", 1.0, lags, np.array([0.3, 0.4, 1.0, 0.4, 0.2]), np.full(5, 0.01))
    assert s.beyond[2] and not s.smooth and s.knee_s == 0.0


def test_the_finding_passes_on_white_noise_and_names_the_interval_on_smooth_noise():
    rng = np.random.default_rng(4)
    white = _measured(rng.normal(size=(5_000, 3)))
    smooth = _measured(gaussian_filter1d(rng.normal(size=(5_000, 3)), 8.0, axis=0))
    assert smoothness_finding([white]).passed
    failed = smoothness_finding([white, smooth])
    assert not failed.passed and failed.figure > 0.9
    assert failed.action == f"--config reference_interval_s={smoothness.recommended_interval_s([smooth]):.3g}"


def test_a_share_at_its_bound_on_a_smooth_residual_says_why_and_what_interval():
    rng = np.random.default_rng(5)
    smooth = _measured(gaussian_filter1d(rng.normal(size=(5_000, 3)), 8.0, axis=0), name="TStick")
    at_top = np.log([1e-3, 1e-3, 1e-5, 1.0, 0.65])
    at_top[3] = GM_LOGIT_BOUND - 0.01
    note = share_at_bound(at_top, [smooth])
    assert "share 0.9997" in note and "smooth at the sampling interval on TStick" in note
    assert "two time scales" not in note
    assert "two time scales" in share_at_bound(at_top, [_measured(rng.normal(size=(5_000, 3)))])


def test_a_share_at_its_bound_on_a_smooth_residual_is_refused_before_sampling():
    """RepoIMU at 100 Hz sampled 750-800 steps per model before stopping; the refusal now comes first,
    and only where both hold: the share at its upper bound and the residual smooth (measured here on a
    maneuver whose residual is smoothed noise, 10 ms apart, in a tracker that does not turn)."""
    from types import SimpleNamespace

    from gyrocal.inference.errormodel import Linearization
    from gyrocal.inference.sampling.refusals import EstimateError, check_representable

    rng = np.random.default_rng(6)
    m = 5_000

    def maneuver(residual):
        z = residual[:, None, :]
        return Linearization("TStick", [("a",)], z, np.zeros((m, 1, 3, 1)), np.zeros((m, 1, 3, 3)),
                             np.tile(np.eye(3), (m, 1, 1)), np.full(m, 0.01), None, z.copy())

    smooth = maneuver(gaussian_filter1d(rng.normal(size=(m, 3)), 8.0, axis=0) * 1e-3)
    white = maneuver(rng.normal(size=(m, 3)) * 1e-3)
    log_sigma = np.log([1e-3, 1e-3, 1e-5, 1.0, 0.65])

    def est(share_logit, lin):
        return SimpleNamespace(log_sigma=np.r_[log_sigma[:3], share_logit, log_sigma[4]],
                               spec=SimpleNamespace(model="correlated"), linearize=lambda maneuvers, k: lin,
                               maneuver_variances=lambda k, group: {"walk": 1e-10})

    maneuvers = [SimpleNamespace(noise_group="all")]
    with pytest.raises(EstimateError, match=r"model correlated: .*share 0\.9997.*smooth at the sampling interval on "
                                            r"TStick.*reference_interval_s=1;.*cannot converge"):
        check_representable(maneuvers, est(GM_LOGIT_BOUND - 0.01, smooth))
    check_representable(maneuvers, est(GM_LOGIT_BOUND - 0.01, white))
    check_representable(maneuvers, est(GM_LOGIT_BOUND - 1.0, smooth))
    check_representable(maneuvers, SimpleNamespace(log_sigma=log_sigma[:3], spec=None))


def test_growth_within_runs_counts_only_the_increments_inside_each_run():
    """A smooth series (white noise through a 20-sample kernel) with a step of 200 sd between two runs:
    counted across the step the increments grow as a walk's (the step's share grows with the lag, the
    smoothness hidden); within the runs as the smooth series' own, and the standard error follows the
    increments actually counted."""
    rng = np.random.default_rng(4)
    r = gaussian_filter1d(rng.normal(size=(4_000, 3)), 20, axis=0)
    r[2_000:] += 200.0 * r.std()
    runs = smoothness.contiguous_runs(np.concatenate([np.arange(2_000), 5_000 + np.arange(2_000)]).astype(float))
    assert list(np.bincount(runs)) == [2_000, 2_000]
    lags, exponent, se = smoothness.growth(r, runs)
    assert exponent[0] > 0.95 and smoothness.growth(r)[1][0] < 0.6, (exponent[0], smoothness.growth(r)[1][0])
    k = lags[2]
    np.testing.assert_allclose(se[2], 0.5 / np.log(2) * np.sqrt(2 / (3 * (4_000 - 2 * k) / k)
                                                              + 2 / (3 * (4_000 - 4 * k) / (2 * k))))


def test_runs_too_short_for_any_lag_give_no_growth():
    lags, exponent, se = smoothness.growth(np.zeros((40, 3)), np.arange(40))
    assert len(lags) == len(exponent) == len(se) == 0
