"""The residual's increment growth (`gyrocal.inference.smoothness`) on series whose variogram is known."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from gyrocal.checks.fit import share_at_bound
from gyrocal.criticism.increments import smoothness_finding
from gyrocal.inference import smoothness
from gyrocal.inference.noisefit import GM_LOGIT_BOUND


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


def test_a_random_walk_is_called_smooth_rarely():
    """The standard error errs against calling a residual smooth: 400 short walks (300 samples), the
    model's fastest growth, are called smooth at most twice (3 se: 0.1 % if it were exact)."""
    rng = np.random.default_rng(2)
    calls = sum(_measured(np.cumsum(rng.normal(size=(300, 3)), axis=0)).smooth for _ in range(400))
    assert calls <= 2


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
    and only where both hold: the share at its upper bound and the residual smooth."""
    from types import SimpleNamespace

    from gyrocal.checks.fit import EstimateError, check_representable

    rng = np.random.default_rng(6)
    smooth = _measured(gaussian_filter1d(rng.normal(size=(5_000, 3)), 8.0, axis=0), name="TStick")
    white = _measured(rng.normal(size=(5_000, 3)))
    log_sigma = np.log([1e-3, 1e-3, 1e-5, 1.0, 0.65])
    est = lambda share_logit: SimpleNamespace(log_sigma=np.r_[log_sigma[:3], share_logit, log_sigma[4]],
                                              spec=SimpleNamespace(model="correlated"))
    with pytest.raises(EstimateError, match=r"model correlated: .*share 0\.9997.*smooth at the sampling interval on "
                                            r"TStick.*reference_interval_s=1,.*cannot converge"):
        check_representable(est(GM_LOGIT_BOUND - 0.01), [smooth])
    check_representable(est(GM_LOGIT_BOUND - 0.01), [white])
    check_representable(est(GM_LOGIT_BOUND - 1.0), [smooth])
    check_representable(SimpleNamespace(log_sigma=log_sigma[:3], spec=None), [smooth])
