"""The reference error's clock chosen from the data (``star_tracker: gm_clock_s_per_rad: auto``): the rule on
the REML of each clock, the choice on simulated campaigns whose error runs on the angle or on time, and the
preprocess step that carries the choice to every maneuver."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from test_angle_clock import GM_ANGLE, _tiny

from gyrocal.inference import clock
from gyrocal.simulation import simulate

from conftest import DATA


def _rows(values):
    return [{"clock_s_per_rad": k, "neg_log_lik": v} for k, v in zip(clock.GRID_S_PER_RAD, values)]


def test_an_angle_clock_is_taken_only_where_it_gains_the_likelihood_ratio_tests_units():
    assert abs(clock.GAIN_MIN - 5.414) < 1e-3   # chi2(1) at p = 0.001, halved
    assert clock.chosen(_rows([0.0, -1.0, -3.0, -5.0, -5.4, -5.0, -4.0])) == 0.0
    assert clock.chosen(_rows([0.0, -1.0, -3.0, -4.0, -5.5, -5.0, -4.0])) == 3000.0


def test_of_the_clocks_within_one_unit_of_the_best_the_smallest_is_taken():
    """A flat tail (the correlation angle fixed, K no longer), shaped as BROAD's slow trial's REML (time
    -36819.4; 3000, 10 000 and 30 000 s/rad -40511.2, -40513.5, -40514.1; the others made up): 10 000 is
    taken where 30 000 is best by 0.6."""
    rows = _rows([-36819.4, -38000.0, -39500.0, -40400.0, -40511.2, -40513.5, -40514.1])
    assert clock.chosen(rows) == 10000.0


def test_on_one_maneuver_whose_error_runs_on_the_angle_the_angle_clock_is_chosen():
    """The fast tier's case: one tiny maneuver, two clocks (time, and the true 3000 s/rad): it gains 22.6
    log-likelihood units (seed 3)."""
    data, *_, boresight = _tiny(GM_ANGLE, 1)
    stated = {"sigma_cross_arcsec": 30.0, "sigma_about_arcsec": 40.0, "arw_deg_sqrt_h": 0.003,
              "boresight_body": boresight.tolist()}
    choice = clock.choose(data, stated, grid=(0.0, 3000.0))
    assert choice.clock_s_per_rad == 3000.0 and choice.grid[1]["gain_over_time"] > 10.0, choice.grid
    assert 0.2 < choice.grid[1]["correlation_angle_rad"] < 5.0   # the truth's: 1 rad


def test_a_clock_whose_fit_fails_is_left_out_and_a_failed_time_clock_or_pilot_keeps_time():
    rows = _rows([0.0, None, -3.0, -4.0, -5.5, float("nan"), -4.0])
    rows[5]["neg_log_lik"] = None   # fitted_grid records a non-finite REML as None, with its error
    assert clock.chosen(rows) == 3000.0
    assert clock.chosen(_rows([None, -10.0, -20.0, -30.0, -40.0, -50.0, -60.0])) == 0.0
    assert clock.chosen(_rows([0.0, None, None, None, None, None, None])) == 0.0
    failed = clock.ClockChoice(0.0, [], failed="the pilot fit failed (singular matrix)")
    assert failed.reason == "the time clock: the pilot fit failed (singular matrix)"
    assert json.loads(json.dumps(failed.record()))["clock_s_per_rad"] == 0.0


@pytest.mark.full  # 30 s each: the whole grid on three maneuvers
@pytest.mark.parametrize("gm, expected", [
    (GM_ANGLE, (1000.0, 3000.0, 10000.0)),
    ({**GM_ANGLE, "gm_tau_s": 30.0, "gm_clock_s_per_rad": 0.0}, (0.0,)),
], ids=["on the angle (3000 s/rad)", "on time (tau 30 s)"])
def test_the_choice_follows_the_clock_the_simulated_error_runs_on(gm, expected):
    """Three tiny maneuvers, the reference error half white and half Gauss-Markov (30 arcsec each way):
    on the angle clock the choice is within a factor of about three of the truth; on time it stays on time."""
    data, *_, boresight = _tiny(gm)
    stated = {"sigma_cross_arcsec": 30.0, "sigma_about_arcsec": 40.0, "arw_deg_sqrt_h": 0.003,
              "boresight_body": boresight.tolist()}
    choice = clock.choose(data, stated)
    assert choice.clock_s_per_rad in expected, choice.grid
    record = json.loads(json.dumps(choice.record()))
    assert record["requested"] == "auto" and record["clock_s_per_rad"] == choice.clock_s_per_rad
    assert [row["clock_s_per_rad"] for row in record["grid"]] == list(clock.GRID_S_PER_RAD)
    assert ("s a radian turned" in choice.reason) == (choice.clock_s_per_rad > 0)


@pytest.mark.full  # 75 s: the pilot and the grid on the tiny campaign, then a correlated model's point estimate
def test_the_preprocess_step_chooses_the_clock_records_why_and_every_maneuver_and_fit_carries_it(tmp_path, config):
    """The tiny campaign with its reference error on the angle clock (3000 s/rad), campaign.yaml asking for
    ``auto``: ``preprocess/gm_clock.json`` says which clock and why, every preprocessed maneuver carries it,
    and a correlated model's point estimate states it (its tau prior's median 30 s + K x 1 rad)."""
    from gyrocal.inference.fit.estimate import PointEstimate
    from gyrocal.pipeline.paths import CampaignPaths
    from gyrocal.pipeline.run import calibrate_campaign
    from gyrocal.pipeline.steps.common import load_maneuvers

    scenario = yaml.safe_load((DATA / "tiny.yaml").read_text())
    scenario["star_tracker"].update(GM_ANGLE)
    (tmp_path / "scenario.yaml").write_text(yaml.safe_dump(scenario))
    simulate.run(tmp_path / "scenario.yaml", tmp_path / "sim")
    meta = tmp_path / "sim" / "campaign" / "campaign.yaml"
    stated = yaml.safe_load(meta.read_text())
    stated["star_tracker"]["gm_clock_s_per_rad"] = "auto"
    meta.write_text(yaml.safe_dump(stated))
    paths = CampaignPaths.under(tmp_path / "out")
    cfg = {**config, "models": {"correlated": ["scale_factor", "misalignment", "bias", "st_correlated_noise"]}}
    ids = calibrate_campaign(tmp_path / "sim" / "campaign", paths, cfg, ["correlated"], figures=False,
                             through="point_estimate")
    record = json.loads(Path(paths.gm_clock).read_text())
    assert record["requested"] == "auto" and record["clock_s_per_rad"] in (1000.0, 3000.0, 10000.0), record
    assert {d.gm_clock_s_per_rad for d in load_maneuvers(paths.maneuvers(ids))} == {record["clock_s_per_rad"]}
    est = PointEstimate.load(paths.model("correlated").point_estimate)
    assert est.stated_noise["gm_clock_s_per_rad"] == record["clock_s_per_rad"]
    assert np.isfinite(est.correlation_time_s) and est.correlation_time_s > 0


@pytest.mark.full  # 2 s each; the fast tier keeps the clock's choice on one maneuver and the rule
@pytest.mark.parametrize("gm, significant", [(GM_ANGLE, True), ({"gm_clock_s_per_rad": 3000.0}, False)],
                         ids=["angle-clock error", "white error"])
def test_on_the_angle_clock_the_ranking_scores_correlated_noise_by_the_exact_likelihood_ratio(gm, significant):
    """The spectral score presumes equal steps; on the clock the ranking takes the REML's likelihood ratio at
    the white model's fit: far beyond chance where the error runs on the clock, within chance where it is white."""
    from dataclasses import replace

    from gyrocal.inference.fit.pilot import pilot
    data, *_, boresight = _tiny(gm, 1)
    data = [replace(d, gm_clock_s_per_rad=3000.0) for d in data]
    stated = {"sigma_cross_arcsec": 30.0, "sigma_about_arcsec": 40.0, "arw_deg_sqrt_h": 0.003,
              "boresight_body": boresight.tolist(), "gm_clock_s_per_rad": 3000.0}
    est, _ = pilot(data, stated)
    ratio = clock.likelihood_ratio(data, est)
    assert ratio["clock_s_per_rad"] == 3000.0
    assert (ratio["chi2"] > 30.0) if significant else (ratio["chi2"] < 13.8), ratio   # 13.8: p = 0.001 on 2 df


@pytest.mark.full  # 50 s: the ranking given each leading candidate, on six tiny maneuvers
def test_on_the_clock_a_deterministic_effect_left_out_is_ranked_above_correlated_noise():
    """White reference noise and a hidden gravity offset (60 arcsec/g), the campaign on a clock of 1000
    s/rad (found by an independent review): correlated noise scored 2433 against the offset's 2417 and led;
    given the offset's columns its ratio falls away, so it is set below it, as on the time clock."""
    from gyrocal.io.scenario import load_scenario
    from gyrocal.study.baseline import baseline_ranking

    scenario = load_scenario(DATA / "tiny.yaml")
    scenario["accelerometer"]["gravity_m_s2"] = 9.81
    scenario["effects"]["gravity_offset_arcsec_per_g"] = 60.0
    campaign, _ = simulate.simulate(scenario, 3)
    campaign.star_tracker["gm_clock_s_per_rad"] = 1000.0
    stated = {"sigma_cross_arcsec": 30.0, "sigma_about_arcsec": 40.0, "arw_deg_sqrt_h": 0.003, "boresight_body": [0, 0, 1]}
    ranking = baseline_ranking(campaign, stated)[3]
    names = [r["name"] for r in ranking]
    assert names[0] == "gravity_offset", ranking[:3]
    noise = ranking[names.index("st_correlated_noise")]
    assert noise["log10_p"] < -6 and "leftover_log10_p" in noise   # significant alone, set below what explains it


@pytest.mark.full  # 20 s
def test_with_the_timing_jitter_in_the_model_the_ratio_counts_it_once():
    """White reference noise and 20 ms of timing jitter at 2 deg/s, the model with st_jitter, on a clock of
    3000 s/rad (found by an independent review): without the jitter in both fits the ratio was 3372 (a
    Gauss-Markov part on the angle clock mimics noise that grows with the rate); with it, none."""
    from gyrocal.inference.fit import classic
    from gyrocal.inference.fit.estimate import point_estimate
    from gyrocal.io.scenario import load_scenario
    from gyrocal.maneuvers import preprocess
    from gyrocal.model import effects
    from gyrocal.model.spec import ModelSpec

    scenario = load_scenario(DATA / "tiny.yaml")
    scenario["effects"]["st_jitter_ms"] = 20.0
    scenario["maneuver_defaults"]["rate_deg_s"] = 2.0
    campaign, _ = simulate.simulate(scenario, 3)
    data = [replace(preprocess.slice_maneuver(campaign, m.id), gm_clock_s_per_rad=3000.0) for m in campaign.maneuvers]
    stated = {"sigma_cross_arcsec": 5.0, "sigma_about_arcsec": 20.0, "arw_deg_sqrt_h": 0.003,
              "boresight_body": [0.3, 0.0, 0.954], "gm_clock_s_per_rad": 3000.0}
    spec = ModelSpec.build("j", effects.resolve("j", list(effects.BASELINE) + ["st_jitter"], {}), data[0].channels)
    est = point_estimate(data, spec, stated, classic.classic_start(data, spec))
    assert clock.likelihood_ratio(data, est)["chi2"] < 13.8   # p = 0.001 on 2 df
