"""The ranking's score of correlated reference noise (`gyrocal.criticism.correlation`)."""

import numpy as np
from scipy import stats

from gyrocal.criticism import correlation, noiseranking


def _ar1(rng, n, phi):
    x = np.zeros(n)
    e = rng.normal(size=n) * np.sqrt(1 - phi**2)
    x[0] = rng.normal()
    for j in range(1, n):
        x[j] = phi * x[j - 1] + e[j]
    return x


def test_the_periodogram_is_the_squared_fft_of_each_series_written_out():
    rng = np.random.default_rng(0)
    w = rng.normal(size=9 * 6)
    power, omega = correlation.periodogram(w, 6, values=2)
    series = w.reshape(9, 6)[:, :2]
    j = np.arange(9)
    dense = [abs(np.sum(series[:, c] * np.exp(-2j * np.pi * k * j / 9))) ** 2 / 9 for k in (1, 2, 3, 4) for c in (0, 1)]
    np.testing.assert_allclose(power, dense, rtol=1e-12)
    np.testing.assert_allclose(omega, np.repeat(2 * np.pi * np.arange(1, 5) / 9, 2))


def test_the_whittle_gain_is_the_likelihood_ratio_written_out_at_its_best_grid_point():
    """At the grid point it returns, the gain equals the profiled Whittle log-likelihood ratio computed
    from its definition, and no other grid point beats it."""
    rng = np.random.default_rng(2)
    power, omega = correlation.periodogram(rng.normal(size=600) + 0.8 * _ar1(rng, 600, np.exp(-1 / 8)), 1, 1)
    gain, share, tau = correlation.whittle_gain(power, omega)

    def ratio(s, t):
        phi = np.exp(-1 / t)
        g = (1 - s) + s * (1 - phi**2) / (1 - 2 * phi * np.cos(omega) + phi**2)
        sigma2 = np.mean(power / g)
        white = -0.5 * np.sum(np.log(np.mean(power)) + power / np.mean(power))
        fitted = -0.5 * np.sum(np.log(sigma2 * g) + power / (sigma2 * g))
        return 2 * (fitted - white)

    np.testing.assert_allclose(gain, ratio(share, tau), rtol=1e-10)
    assert all(ratio(s, t) <= gain + 1e-9 for s in correlation.SHARE_GRID for t in correlation.TAU_GRID_SAMPLES)


def test_white_innovations_give_a_chi_square_sized_ratio_and_gauss_markov_ones_find_their_time():
    rng = np.random.default_rng(1)
    white = [correlation.score([correlation.periodogram(rng.normal(size=3 * 4_000), 3)])["chi2"] for _ in range(20)]
    assert np.mean(white) < 6 and max(white) < 20, white
    gm = rng.normal(size=(4_000, 3)) + np.column_stack([_ar1(rng, 4_000, np.exp(-1 / 30)) for _ in range(3)])
    found = correlation.score([correlation.periodogram(gm.ravel(), 3)])
    assert found["chi2"] > 500 and 15 <= found["tau_samples"] <= 60 and 0.3 <= found["share"] <= 0.7, found
    assert found["log10_p"] == round(-found["chi2"] / 2 / np.log(10), 2)


def test_a_large_smooth_systematic_error_gains_only_as_the_log_of_its_energy():
    """A slow sine in white innovations, 10 and 100 times larger in energy: the ratio grows by the same
    step per factor of ten, as the log of the energy, where a score test on the sine's own column grows
    in proportion (an autocorrelation sum grew as the energy squared, and named a large left-out
    effect as noise)."""
    rng = np.random.default_rng(3)
    base = rng.normal(size=(3_000, 3))
    t = np.arange(3_000)[:, None]
    gains = [correlation.score([correlation.periodogram((base + a * np.sin(2 * np.pi * t / 1_500)).ravel(), 3)])["chi2"]
             for a in (3.0, np.sqrt(10) * 3.0, 30.0)]
    steps = np.diff(gains)
    assert abs(steps[1] / steps[0] - 1) < 0.25 and gains[2] < 5 * gains[0], gains  # as log(energy), not energy


def _fitted(name: str, seed: int, **changes):
    """tests/data/<name>.yaml simulated with ``seed`` (``changes``: star_tracker and effects keys), the
    white baseline fitted and ranked (`gyrocal.study.baseline`)."""
    from pathlib import Path

    import yaml

    from gyrocal.simulation import simulate
    from gyrocal.study.baseline import baseline_ranking

    root = Path(__file__).resolve().parents[1]
    scenario = simulate.load_scenario(root / f"tests/data/{name}.yaml")
    for key, value in changes.items():
        section, key = key.split("__")
        scenario[section][key] = value
    scenario["seed"] = seed
    cfg = yaml.safe_load((root / "config/config.yaml").read_text())
    return baseline_ranking(simulate.simulate(scenario)[0], cfg["noise"])


def test_a_white_baseline_on_gauss_markov_noise_of_30_s_names_it_first_where_the_lag_1_score_did_not():
    """The Gauss-Markov validation's campaign kind (tests/data/hidden_st_correlated_noise.yaml, white 5/20
    arcsec plus a Gauss-Markov part as large, tau 30 s), seed 4: the lag-1 score alone (log10 p -10.7)
    ranked below a slow signature (rate_sign, -25.9); the likelihood ratio ranks the correlated noise first."""
    _, _, white, ranking = _fitted("hidden_st_correlated_noise", 4, star_tracker__gm_sigma_cross_arcsec=5.0,
                                   star_tracker__gm_sigma_about_arcsec=20.0, star_tracker__gm_tau_s=30.0,
                                   effects__st_correlation_time_s=0.0)
    lag1_alone = stats.chi2.logsf(white["z"] ** 2, 1) / np.log(10)
    deterministic = [r for r in ranking if r["name"] != "st_correlated_noise"]
    assert deterministic[0]["log10_p"] < lag1_alone - 5, (deterministic[0], lag1_alone)
    assert ranking[0]["name"] == "st_correlated_noise" and ranking[0]["chi2_drop"] == white["gauss_markov"]["chi2"]
    assert ranking[0]["log10_p"] < deterministic[0]["log10_p"] - 50


def test_a_noise_leading_an_effect_that_leaves_it_white_is_set_below_it():
    """tests/data/hidden_bias_drift.yaml at ten times its drift (20 deg/h/h), seed 0: given the drift's
    columns the innovations are white, so the noise, were it ahead of the drift, would be set below it
    (`noiseranking.demote_explained`); here the likelihood ratio already ranks it second (log10 p -823
    against -1 087), and the check, given a rank it is handed, moves it."""
    from gyrocal.model import effects

    maneuvers, est, _, ranking = _fitted("hidden_bias_drift", 0, effects__bias_drift_deg_h_per_h=20.0)
    assert [r["name"] for r in ranking[:2]] == ["bias_drift", "st_correlated_noise"]
    given_drift = noiseranking.noise_score_given(maneuvers, est, [effects.LIBRARY["bias_drift"]])["log10_p"]
    assert given_drift > noiseranking.LEFTOVER_LOG10_P
    swapped = [ranking[1], ranking[0]] + ranking[2:]
    noiseranking.demote_explained(swapped, maneuvers, est, {"bias_drift": effects.LIBRARY["bias_drift"]}, 5)
    assert [r["name"] for r in swapped[:2]] == ["bias_drift", "st_correlated_noise"]
    assert swapped[1]["leftover_log10_p"] == given_drift


def test_a_correlation_time_at_the_search_end_says_a_systematic_error_fits_as_well():
    end = float(correlation.TAU_GRID_SAMPLES[-1])
    assert "slow systematic error" in correlation.caveat({"chi2": 3733.6, "tau_samples": end})
    assert correlation.caveat({"chi2": 600.0, "tau_samples": 15.8}) == ""
    assert correlation.caveat({"chi2": 0.0, "tau_samples": end}) == ""
