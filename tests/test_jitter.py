"""The reference's timing jitter (`st_jitter`): its covariance component, its REML, its signature in the
ranking, and a simulated campaign with and without it."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from test_numerics import BORESIGHT, SETS, M, band_to_dense, dense_covariance, difference_matrix, tiny_linearization

from gyrocal.criticism import rategrowth
from gyrocal.inference.noise import covariance

ROOT = Path(__file__).resolve().parents[1]
VAR = {"cross": 2.0e-10, "about": 3.5e-9, "walk": 4.0e-12, "jitter": 2.5e-5}


def _with_rate(lin, seed=1):
    rate = np.random.default_rng(seed).normal(0.0, 2.0, (M, 3))
    return replace(lin, st_body_rate=rate)


def test_jitter_component_is_sigma_t_squared_omega_omega_t_per_sample_differenced():
    """The banded covariance with the jitter equals the dense one: the white model's plus, at each reference
    sample, ``sigma_t^2 R omega omega^T R^T`` shared by the sets, first-differenced."""
    lin = _with_rate(tiny_linearization())
    nz = covariance.build(lin, BORESIGHT, jitter=True)
    t = difference_matrix(M, 3 * SETS)
    jit = np.zeros((M, SETS, 3, M, SETS, 3))
    for j in range(M):
        v = lin.st_matrix[j] @ lin.st_body_rate[j]
        jit[j, :, :, j, :, :] = VAR["jitter"] * np.outer(v, v)[None, :, None, :]
    dense = dense_covariance(lin, VAR) + jit.reshape(M * SETS * 3, -1)
    expected = t @ dense @ t.T
    got = band_to_dense(nz.covariance(VAR))
    assert np.abs(got - expected).max() < 1e-12 * np.abs(expected).max()


def test_without_jitter_the_structure_is_the_white_one_to_the_bit():
    lin = _with_rate(tiny_linearization())
    white = covariance.build(lin, BORESIGHT)
    assert "jitter" not in white.components
    off = {k: v for k, v in VAR.items() if k != "jitter"}
    np.testing.assert_array_equal(white.covariance(off), covariance.build(replace(lin, st_body_rate=None),
                                                                          BORESIGHT).covariance(off))


def test_jitter_scale_is_in_ms_at_the_edges_and_seconds_inside():
    stated = {"sigma_cross_arcsec": 10.0, "sigma_about_arcsec": 40.0, "arw_deg_sqrt_h": 0.003, "st_jitter_ms": 4.0}
    log_sigma = covariance.log_sigma_of(stated, jitter=True)
    assert len(log_sigma) == 4 and np.isclose(np.exp(log_sigma[3]), 4e-3)
    assert np.isclose(covariance.variances(log_sigma)["jitter"], 1.6e-5)
    assert covariance.stated_scales(log_sigma)["st_jitter_ms"] == pytest.approx(4.0)
    np.testing.assert_allclose(covariance.absolute_of(log_sigma[0], covariance.ratios_of(log_sigma)), log_sigma)
    unstated = {k: v for k, v in stated.items() if k != "st_jitter_ms"}
    assert np.exp(covariance.log_sigma_of(unstated, jitter=True)[3]) == pytest.approx(1e-3)  # the prior's median


def test_rate_growth_finds_variance_growing_with_the_squared_rate_and_not_constant_variance():
    rng = np.random.default_rng(4)
    rate = rng.uniform(0.0, 1.0, (3000, 3))
    q = rategrowth.per_sample(np.zeros(3000 * 6), 6, rate)[1]
    quiet = rategrowth.score([(rng.normal(size=q.size), q)])
    grown = rategrowth.score([(rng.normal(size=q.size) * np.sqrt(1 + 2.0 * q), q)])
    assert quiet["chi2"] < 10 and grown["chi2"] > 150, (quiet, grown)  # 267 here
    assert 1.0 < grown["growth_per_rad2_s2"] < 4.0


def _campaign(jitter_ms: float, seed: int = 1, **effects):
    from gyrocal.simulation import simulate

    scenario = simulate.load_scenario(ROOT / "tests/data/hidden_st_jitter.yaml")
    scenario["effects"]["st_jitter_ms"] = jitter_ms
    scenario["effects"].update(effects)
    scenario["seed"] = seed
    return simulate.simulate(scenario)


def _fitted(campaign, names):
    from gyrocal.inference.fit import classic
    from gyrocal.inference.fit.estimate import point_estimate
    from gyrocal.maneuvers import preprocess
    from gyrocal.model import effects
    from gyrocal.model.spec import ModelSpec

    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    stated = covariance.noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    spec = ModelSpec.build("m", effects.resolve("m", names, {}), maneuvers[0].channels)
    return maneuvers, point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))


BASE = ["scale_factor", "misalignment", "bias"]


def test_reml_finds_the_simulated_jitter_and_none_where_there_is_none():
    """5 ms of jitter at 5 deg/s (90 arcsec against a 5 arcsec tracker): the REML finds it within 20 %, and
    puts the tracker back at its 5 arcsec; without jitter it goes to its floor (1 us) and the other scales
    are the white model's."""
    jittered = _fitted(_campaign(5.0)[0], BASE + ["st_jitter"])[1]
    scales = covariance.stated_scales(jittered.log_sigma)
    assert 4.0 < scales["st_jitter_ms"] < 6.0 and 4.0 < scales["sigma_cross_arcsec"] < 6.5, scales
    campaign = _campaign(0.0)[0]
    clean = covariance.stated_scales(_fitted(campaign, BASE + ["st_jitter"])[1].log_sigma)
    white = covariance.stated_scales(_fitted(campaign, BASE)[1].log_sigma)
    assert clean["st_jitter_ms"] < 0.05, clean
    for key in ("sigma_cross_arcsec", "sigma_about_arcsec"):
        assert clean[key] == pytest.approx(white[key], rel=0.01)


def test_the_ranking_names_the_jitter_and_sets_it_below_a_latency_that_explains_it():
    from gyrocal.study.baseline import baseline_ranking

    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    _, _, white, ranking = baseline_ranking(_campaign(5.0)[0], cfg["noise"])
    assert ranking[0]["name"] == "st_jitter" and white["rate_growth"]["log10_p"] < -100
    _, _, _, ranking = baseline_ranking(_campaign(0.0, seed=2, st_latency_s=0.02)[0], cfg["noise"])
    names = [r["name"] for r in ranking]
    assert names[0] == "st_latency" and names.index("st_jitter") > 0
    assert ranking[names.index("st_jitter")]["leftover_log10_p"] > -2


def _sampled(campaign, truth, names):
    """The posterior (a short run) of a model on the campaign: its draws of the timing jitter (ms, None
    without it) and each channel parameter's z-score against the truth."""
    from gyrocal.inference.sampling import posterior
    from gyrocal.inference.sampling.priors import model_priors

    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    maneuvers, est = _fitted(campaign, names)
    ready = posterior.prepare(maneuvers, est, model_priors(est, cfg["priors"]), cfg["grid"])
    sampler = {**cfg["sampler"], "walkers": 32, "ensembles": 2, "burn_steps": 100, "initial_steps": 100,
               "min_tau_multiple": 20}
    draws = posterior.run(ready, sampler, 1).result.chains
    draws = draws.reshape(-1, draws.shape[-1])
    p = len(est.spec.labels)
    theta = est.theta + draws[:, :p]
    z = {}
    for i, spec in enumerate(est.spec.parameters):
        true = truth["parameters"][spec.owner].get(spec.name, 0.0) * spec.si_per_unit
        z[spec.label] = (theta[:, i].mean() - true) / theta[:, i].std()
    jitter = np.exp(draws[:, p + 3]) * 1e3 if est.spec.jitter_noise else None
    return jitter, z


@pytest.mark.full  # 7 s; the fast tier keeps the REML finding the jitter and the ranking naming it
def test_sampled_jitter_and_the_calibrations_intervals_cover_the_truth():
    """With 5 ms of jitter the posterior's 95 % interval of sigma_t holds 5 ms (4.2-5.5 here) and every
    channel parameter lies within 3 sd of its truth; without jitter sigma_t's posterior stays far below
    it (consistent with 0 under its prior) and the channel estimates are the white model's."""
    campaign, truth = _campaign(5.0)
    jitter, z = _sampled(campaign, truth, BASE + ["st_jitter"])
    low, high = np.percentile(jitter, [2.5, 97.5])
    assert low < 5.0 < high and high / low < 2.0, (low, high)
    assert max(abs(v) for v in z.values()) < 3.0, z
    assert np.mean([abs(v) < 1.96 for v in z.values()]) >= 0.8, z
    campaign, truth = _campaign(0.0)
    jitter, z = _sampled(campaign, truth, BASE + ["st_jitter"])
    assert np.percentile(jitter, 97.5) < 1.0, np.percentile(jitter, [2.5, 50, 97.5])
    _, z_white = _sampled(campaign, truth, BASE)
    assert max(abs(z[k] - z_white[k]) for k in z) < 0.2, {k: z[k] - z_white[k] for k in z}
