"""The ranking's score of correlated reference noise (`gyrocal.criticism.correlation`)."""

import numpy as np
import pytest
from scipy import stats

from gyrocal.criticism import correlation, noiseranking


def test_autocovariances_equal_the_dot_products_of_the_samples_lagged():
    rng = np.random.default_rng(0)
    w = rng.normal(size=7 * 6)
    acov = correlation.autocovariances(w, 6, max_lag=9)
    series = w.reshape(7, 6)
    dense = [float(np.sum(series[k:] * series[:len(series) - k])) for k in range(7)]
    np.testing.assert_allclose(acov[:7], dense, rtol=1e-12)
    assert len(acov) == 10 and np.all(acov[7:] == 0.0)


def test_the_scan_is_standard_normal_on_white_innovations_and_peaks_at_the_true_correlation_time():
    rng = np.random.default_rng(1)
    n = 20_000
    white = correlation.scan(correlation.autocovariances(rng.normal(size=n), 1), n)
    assert np.all(np.abs(white) < 3), white
    phi = np.exp(-1 / 30)
    gm = np.zeros(n)
    e = rng.normal(size=n) * np.sqrt(1 - phi**2)
    for j in range(1, n):
        gm[j] = phi * gm[j - 1] + e[j]
    z = correlation.scan(correlation.autocovariances(rng.normal(size=n) + 0.3 * gm, 1), n)
    assert correlation.SCAN_TAU_SAMPLES[int(np.argmax(z))] == 30.0 and z.max() > 10, z


def test_the_scan_is_the_locally_most_powerful_weighted_sum_written_out():
    rho = np.array([0.1, 0.05, -0.02])
    acov = np.concatenate([[1.0], rho])
    phi = np.exp(-1 / 3.0)
    expected = np.sqrt(400) * (phi * 0.1 + phi**2 * 0.05 - phi**3 * 0.02) / np.sqrt(phi**2 + phi**4 + phi**6)
    np.testing.assert_allclose(correlation.scan(acov, 400, (3.0,)), [expected])


@pytest.mark.parametrize("z_lag1, z_scan, expected", [
    (3.0, [0.0, 0.0], np.log(2 * stats.norm.sf(3.0) / correlation.LAG1_WEIGHT)),
    (0.5, [9.0, 2.0], np.log(stats.norm.sf(9.0) / ((1 - correlation.LAG1_WEIGHT) / 2))),
    (0.0, [0.0], 0.0),
])
def test_log_p_takes_the_smaller_of_the_weighted_bounds(z_lag1, z_scan, expected):
    np.testing.assert_allclose(correlation.log_p(z_lag1, np.array(z_scan)), expected, rtol=1e-10)


@pytest.mark.parametrize("log_p", [np.log(1e-8), -699.0, -701.0, -1000.0, -5000.0])
def test_the_chi2_equivalent_has_the_same_p_value_below_the_doubles_too(log_p):
    x = correlation.chi2_equivalent(log_p)
    np.testing.assert_allclose(np.log(2) + stats.norm.logsf(np.sqrt(x)), log_p, rtol=1e-6)


def test_a_white_baseline_on_gauss_markov_noise_of_30_s_names_it_first_where_the_lag_1_score_did_not():
    """The Gauss-Markov validation's campaign kind (tests/data/hidden_st_correlated_noise.yaml, white 5/20
    arcsec plus a Gauss-Markov part as large, tau 30 s), seed 4: the lag-1 score alone (log10 p -10.7)
    ranked below a slow signature (rate_sign, -25.9); the scan ranks the correlated noise first."""
    from pathlib import Path

    import yaml

    from gyrocal.criticism import diagnostics
    from gyrocal.inference import classic, preprocess
    from gyrocal.inference.estimate import linearize_all, point_estimate
    from gyrocal.inference.noise import noise_knowledge
    from gyrocal.model import effects
    from gyrocal.model.spec import ModelSpec
    from gyrocal.simulation import simulate

    root = Path(__file__).resolve().parents[1]
    scenario = simulate.load_scenario(root / "tests/data/hidden_st_correlated_noise.yaml")
    scenario["star_tracker"].update(gm_sigma_cross_arcsec=5.0, gm_sigma_about_arcsec=20.0, gm_tau_s=30.0)
    scenario["effects"]["st_correlation_time_s"] = 0.0
    scenario["seed"] = 4
    campaign, _ = simulate.simulate(scenario)
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    cfg = yaml.safe_load((root / "config/config.yaml").read_text())
    stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    spec = ModelSpec.build("baseline", effects.resolve("baseline", list(effects.BASELINE), {}), maneuvers[0].channels)
    est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    lins, noises = linearize_all(maneuvers, est)
    white = diagnostics.whiteness(maneuvers, zip(lins, noises), est)
    ranking, _ = diagnostics.rank(maneuvers, est, list(maneuvers[0].extras), (), white)
    lag1_alone = stats.chi2.logsf(white["z"] ** 2, 1) / np.log(10)
    deterministic = [r for r in ranking if r["name"] != "st_correlated_noise"]
    assert deterministic[0]["log10_p"] < lag1_alone - 5, (deterministic[0], lag1_alone)
    assert ranking[0]["name"] == "st_correlated_noise" and ranking[0]["log10_p"] == white["gauss_markov_scan"]["log10_p"]
    assert ranking[0]["log10_p"] < deterministic[0]["log10_p"] - 20


def test_a_large_hidden_bias_drift_is_named_though_its_correlation_outscores_it():
    """tests/data/hidden_bias_drift.yaml at ten times its drift (20 deg/h/h), seed 0: the scan scores the
    correlation it leaves (log10 p -13 767) far beyond the drift's own score test (-1 087), but with the
    drift's columns fitted the innovations are white (found by an independent review): the drift is
    ranked first, the noise after it."""
    from pathlib import Path

    import yaml

    from gyrocal.criticism import diagnostics
    from gyrocal.inference import classic, preprocess
    from gyrocal.inference.estimate import linearize_all, point_estimate
    from gyrocal.inference.noise import noise_knowledge
    from gyrocal.model import effects
    from gyrocal.model.spec import ModelSpec
    from gyrocal.simulation import simulate

    root = Path(__file__).resolve().parents[1]
    scenario = simulate.load_scenario(root / "tests/data/hidden_bias_drift.yaml")
    scenario["effects"]["bias_drift_deg_h_per_h"] = 20.0
    scenario["seed"] = 0
    campaign, _ = simulate.simulate(scenario)
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    cfg = yaml.safe_load((root / "config/config.yaml").read_text())
    stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    spec = ModelSpec.build("baseline", effects.resolve("baseline", list(effects.BASELINE), {}), maneuvers[0].channels)
    est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    lins, noises = linearize_all(maneuvers, est)
    white = diagnostics.whiteness(maneuvers, zip(lins, noises), est)
    ranking, _ = diagnostics.rank(maneuvers, est, list(maneuvers[0].extras), (), white)
    names = [r["name"] for r in ranking]
    assert names[:2] == ["bias_drift", "st_correlated_noise"]
    assert ranking[1]["log10_p"] < ranking[0]["log10_p"] - 10_000
    given_drift = noiseranking.noise_score_given(maneuvers, est, [effects.LIBRARY["bias_drift"]])["log10_p"]
    assert given_drift > noiseranking.LEFTOVER_LOG10_P
