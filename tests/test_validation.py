"""The validation study's arithmetic, checked against known truths on small synthetic inputs."""

import numpy as np
import pandas as pd
import pytest

from gyrocal.model import channels as ch
from gyrocal.study import campaign as study
from gyrocal.study import tables as validation


def test_truth_is_drawn_from_the_configured_prior_within_its_bounds():
    spec = study.prior_spec(ch.MOM_CHANNELS, {"sf_sd_ppm": 100.0, "mis_bound_arcsec": 150.0})
    rng = np.random.default_rng(3)
    draws = [study.draw_truth(spec, rng) for _ in range(400)]
    sf = np.array([d["dtg2_yaw"]["sf_pos"] for d in draws])
    mis = np.array([d["dtg2_yaw"]["mis_roll"] for d in draws])
    assert abs(sf.std() - 100.0) < 10.0 and abs(sf.mean()) < 15.0
    assert np.abs(mis).max() <= 150.0 and mis.std() < 100.0  # truncated at the bound, not at the 1000" sd
    assert set(draws[0]) == {c.name for c in ch.MOM_CHANNELS}


def test_ranks_of_a_calibrated_posterior_are_uniform():
    """Truth and draws from the same normal: every rank 0..L equally likely."""
    rng = np.random.default_rng(5)
    ranks = np.concatenate([study.sbc_rank(rng.normal(size=(99, 4)), rng.normal(size=4), rng) for _ in range(500)])
    counts = validation.sbc_histogram(ranks, 99)
    assert counts.sum() == 2000 and validation.uniformity_p(counts, 99) > 0.001
    narrow = np.concatenate([study.sbc_rank(0.5 * rng.normal(size=(99, 4)), rng.normal(size=4), rng)
                             for _ in range(500)])
    assert validation.uniformity_p(validation.sbc_histogram(narrow, 99), 99) < 1e-6  # overconfident: U-shaped


def test_uniform_ranks_pass_the_uniformity_test_when_the_bins_hold_unequal_numbers_of_ranks():
    """100 draws give 101 ranks, so the first of 10 bins holds 11 of them: every rank 0..100 seen
    1 000 times must give p = 1 (against equal bins it gave p ~ 1e-15)."""
    ranks = np.repeat(np.arange(101), 1000)
    counts = validation.sbc_histogram(ranks, 100)
    assert counts.tolist() == [11000] + [10000] * 9
    assert validation.sbc_bin_shares(100) == pytest.approx([0.11 * 100 / 101] + [10 / 101] * 9)
    assert validation.uniformity_p(counts, 100) == pytest.approx(1.0)
    assert validation.uniformity_p(validation.sbc_histogram(np.repeat(np.arange(100), 1000), 99), 99) == pytest.approx(1.0)


def test_each_study_campaign_samples_its_posterior_with_its_own_seed():
    """One sampler seed for every campaign made their draws nearly the same (SBC ranks not
    independent); each now has its own, reproducibly, apart from its simulation seed."""
    seeds = [study.sampler_seed(1, i) for i in range(200)]
    assert len(set(seeds)) == 200 and seeds == [study.sampler_seed(1, i) for i in range(200)]
    assert not {1 * 100003 + i for i in range(200)} & set(seeds)
    assert study.sampler_seed(2, 0) != seeds[0]


def test_ties_share_their_rank_at_random():
    draws = np.zeros((9, 1))
    ranks = [int(study.sbc_rank(draws, np.zeros(1), np.random.default_rng(s))[0]) for s in range(200)]
    assert min(ranks) == 0 and max(ranks) == 9


def test_thinned_draws_are_an_autocorrelation_time_apart():
    steps, walkers, kept = 400, 64, 250
    step_of = np.linspace(0, steps * walkers - 1, kept).astype(int) // walkers
    draws = np.broadcast_to(step_of[None, :, None], (4, kept, 2)).astype(float)
    thin = study.thinned_draws(draws, steps, walkers, tau_steps=5.0, per_chain=25)
    assert thin.shape == (100, 2)
    picked = thin[:25, 0]
    assert np.all(np.diff(picked) >= 5) and np.all(np.abs(picked - (np.arange(25) + 0.5) * 16) <= 2)
    with pytest.raises(ValueError, match="autocorrelation"):
        study.thinned_draws(draws, steps, walkers, tau_steps=20.0, per_chain=25)


def test_efficient_estimator_band_holds_one():
    lo, hi = validation.efficiency_interval(200)
    assert lo < 1 < hi and lo > 0.85 and hi < 1.2


def test_efficiency_confidence_interval_covers_the_true_efficiency():
    rng = np.random.default_rng(5)
    n, crlb, sigma = 200, 1.0, 1.0 / np.sqrt(0.8)  # true efficiency 0.8
    efficiency = crlb**2 / np.mean(rng.normal(0, sigma, (4000, n)) ** 2, axis=1)
    lo, hi = validation.efficiency_confidence(efficiency, n)
    assert np.mean((lo <= 0.8) & (hi >= 0.8)) == pytest.approx(0.95, abs=0.01)
    assert np.mean(hi < 0.8) == pytest.approx(0.025, abs=0.008)


def test_clustered_interval_is_binomial_for_independent_trials():
    hit = np.r_[np.ones(180), np.zeros(20)]
    lo, hi, n_eff = validation.clustered_interval(hit, np.arange(200))
    assert n_eff == pytest.approx(200) and (lo, hi) == pytest.approx(validation.binomial_interval(180, 200))


def test_clustered_interval_counts_campaigns_whose_trials_agree():
    """Ten identical trials per campaign carry one campaign's information: about 100 trials, not 1000."""
    rng = np.random.default_rng(3)
    per_campaign = rng.random(100) < 0.9
    hit, campaign = np.repeat(per_campaign, 10), np.repeat(np.arange(100), 10)
    lo, hi, n_eff = validation.clustered_interval(hit, campaign)
    from scipy.stats import t
    assert n_eff == pytest.approx(100 * (t.ppf(0.975, 999) / t.ppf(0.975, 99)) ** 2)
    assert (lo, hi) == pytest.approx(validation.binomial_interval(int(per_campaign.sum()), 100), abs=5e-3)


def test_clustered_interval_covers_a_clustered_rate():
    """Campaigns of 24 trials sharing a random effect: the interval holds the true rate about 95 % of
    the time, where the binomial one, which takes the 4800 trials as independent, does not."""
    rng = np.random.default_rng(4)
    campaign = np.repeat(np.arange(200), 24)
    held, held_binomial = 0, 0
    for _ in range(400):
        shared = rng.normal(0, 1, 200)[campaign]
        hit = np.abs(0.6 * shared + 0.8 * rng.normal(0, 1, len(campaign))) < 1.959964
        lo, hi, _ = validation.clustered_interval(hit, campaign)
        held += lo <= 0.95 <= hi
        b_lo, b_hi = validation.binomial_interval(int(hit.sum()), len(hit))
        held_binomial += b_lo <= 0.95 <= b_hi
    assert held / 400 == pytest.approx(0.95, abs=0.03) and held_binomial / 400 < 0.85


def test_clustered_interval_holds_with_few_campaigns():
    """Nine campaigns of 24 trials with a strong shared effect, as an effect group of the study has:
    the degrees-of-freedom correction keeps the interval near its level."""
    rng = np.random.default_rng(6)
    campaign = np.repeat(np.arange(9), 24)
    held = 0
    for _ in range(2000):
        shared = rng.normal(0, 1, 9)[campaign]
        hit = np.abs(0.6 * shared + 0.8 * rng.normal(0, 1, len(campaign))) < 1.959964
        lo, hi, _ = validation.clustered_interval(hit, campaign)
        held += lo <= 0.95 <= hi
    assert held / 2000 > 0.92


def _records(errors, sd, truth=0.0):
    """Synthetic records of one parameter: posterior mean = truth + error, normal quantiles of sd."""
    from scipy.stats import norm
    out = []
    for i, e in enumerate(errors):
        q = {c: truth + e + norm.ppf(p) * sd for c, p in zip(study.QUANTILE_COLUMNS, study.QUANTILES)}
        out.append({"group": "clean", "magnitude": 0.0, "index": i, "parameters": [
            {"model": "baseline", "label": "a.sf_pos", "channel": "a", "parameter": "sf_pos", "unit": "ppm",
             "core": True, "truth": truth, "wls": truth + e, "mean": truth + e, "sd": sd, **q, "sbc_rank": 0,
             "sbc_draws": 99, "crlb_sd": sd, "converged": True, "classic_paper": truth + 3 * e,
             "classic_holds": truth + 1.5 * e}]})
    return out


def test_coverage_and_accuracy_of_a_calibrated_estimator():
    rng = np.random.default_rng(11)
    params = validation.parameter_table(_records(rng.normal(0, 2.0, 4000), 2.0))
    cov = validation.coverage(validation.clean_baseline(params)).set_index("level")
    for level in (0.5, 0.9, 0.95):
        assert cov.loc[level, "rate_lo"] < level < cov.loc[level, "rate_hi"]
    acc = validation.accuracy(params).iloc[0]
    assert acc["efficiency"] == pytest.approx(1.0, abs=0.06)
    assert acc["efficiency_lo"] < 1.0 < acc["efficiency_hi"] and acc["efficiency_hi"] - acc["efficiency_lo"] < 0.1
    assert acc["paper_over_posterior"] == pytest.approx(3.0) and acc["holds_over_posterior"] == pytest.approx(1.5)
    assert acc["paper_over_crlb"] == pytest.approx(3.0 * acc["rmse_mean"] / 2.0)
    assert validation.pooled_efficiency(params) == pytest.approx(acc["efficiency"])


def test_a_study_of_clean_campaigns_alone_has_an_empty_extended_coverage_table():
    params = validation.parameter_table(_records(np.random.default_rng(13).normal(0, 2.0, 50), 2.0))
    table = validation.extended_coverage(params)
    assert table.empty and {"group", "kind", "rate", "max_abs_z"} <= set(table.columns)
    assert validation.detection(params).empty and "misfit" in validation.detection(params).columns


def test_overconfident_intervals_undercover():
    rng = np.random.default_rng(12)
    params = validation.parameter_table(_records(rng.normal(0, 2.0, 2000), 1.0))
    cov = validation.coverage(validation.clean_baseline(params)).set_index("level")
    assert cov.loc[0.95, "rate_hi"] < 0.8


def test_binomial_interval_matches_clopper_pearson():
    assert validation.binomial_interval(0, 200)[1] == pytest.approx(1 - 0.025 ** (1 / 200), rel=1e-6)
    lo, hi = validation.binomial_interval(190, 200)
    assert lo < 0.95 < hi


def test_error_rates_compare_the_checks_with_their_null():
    rng = np.random.default_rng(13)
    n = 2000
    models = pd.DataFrame({"group": "clean", "model": "baseline", "misfit": False, "candidates": 8,
                           "failed:structure": False,
                           "top_log10_p": np.log10(rng.uniform(size=(n, 8)).min(axis=1)),
                           "whiteness_z": rng.normal(size=n)})
    rates = validation.error_rates(models, {"structure_log10_p_min": -6.0, "whiteness_z_max": 5.0}).set_index("test")
    for test in ("structure, top p < 0.05", "whiteness |z| > 1.96"):
        assert rates.loc[test, "rate_lo"] < rates.loc[test, "nominal"] < rates.loc[test, "rate_hi"]
    assert rates.loc["misfit (configured thresholds)", "nominal"] == pytest.approx(8e-6 + 5.7e-7, rel=0.01)


@pytest.mark.full
def test_study_workflow_runs_end_to_end_on_tiny_campaigns(tmp_path):
    """Two clean campaigns and one with a bias drift through the study's Snakefile: every table is
    written, the truths come back, and the drift is caught by the baseline and recovered by its model
    (flown at 4 prior sd, so the prior pulls the posterior mean toward zero: between it and the WLS)."""
    import json
    import subprocess
    import sys

    import yaml

    from conftest import DATA, ROOT
    cfg = yaml.safe_load((ROOT / "config" / "study.yaml").read_text())
    lab = tmp_path / "lab.yaml"  # an effect per g flies its own scenario, in a lab
    lab.write_text(yaml.safe_dump({"base": str(DATA / "tiny.yaml"), "accelerometer": {"gravity_m_s2": 9.80665}}))
    cfg.update(scenario=str(DATA / "tiny.yaml"), results=str(tmp_path / "study"), clean=2, chunk=2, repeats=1,
               effects={"bias_drift": {"simulator_key": "bias_drift_deg_h_per_h", "magnitudes": [2.0],
                                       "model": "bias_drift"},
                        "g_sensitivity": {"simulator_key": "g_sensitivity_deg_s_per_g", "magnitudes": [0.003],
                                          "model": "g_sensitivity", "scenario": str(lab)}})
    cfg["calibration"] = str(ROOT / cfg["calibration"])
    (tmp_path / "study.yaml").write_text(yaml.safe_dump(cfg))
    subprocess.run([sys.executable, "-m", "snakemake", "-s", str(ROOT / "workflow/study/Snakefile"), "--cores", "2",
                    "--configfile", str(tmp_path / "study.yaml"), "-q", "--directory", str(tmp_path)], check=True)
    out = tmp_path / "study"
    params = pd.read_csv(out / "parameters.csv")
    assert len(params[params["group"] == "clean"]) == 2 * 24
    detection = pd.read_csv(out / "detection.csv").set_index("effect")
    assert (detection["misfit"] == 1.0).all() and (detection["ranked_first"] == 1.0).all()
    g = params[(params["model"] == "g_sensitivity") & ~params["core"]]
    assert len(g) == 18 and np.all(np.abs(g["mean"] - 0.003) < 4 * g["sd"])
    drift = params[(params["model"] == "bias_drift") & ~params["core"]]
    assert len(drift) == 6 and np.all(np.abs(drift["wls"] - 2.0) < 3 * drift["crlb_sd"])
    assert np.all((drift["mean"] > 0) & (drift["mean"] < drift["wls"]))
    assert json.loads((out / "summary.json").read_text())["campaigns"] == 4
    for name in ("accuracy", "coverage", "sbc", "detection"):
        assert (out / f"{name}.png").stat().st_size > 1000


def test_detection_counts_a_signature_that_names_the_same_physics():
    models = pd.DataFrame({"group": "st_latency", "model": "baseline", "magnitude": 0.01,
                           "misfit": [True, True, False], "top": ["acceleration", "st_latency", "acceleration"]})
    row = validation.detection(models, {"st_latency": ["acceleration"]}).iloc[0]
    assert row["ranked_first"] == pytest.approx(1 / 3) and row["named_first"] == 1.0
    assert row["detected_and_first"] == pytest.approx(2 / 3)
