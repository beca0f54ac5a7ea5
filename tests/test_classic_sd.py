"""The classic method's sd (delta method over the stated noise) and where it takes the bias from."""

import numpy as np
import pytest

from gyrocal.inference.fit import classic
from gyrocal.maneuvers import preprocess
from gyrocal.model import spec
from gyrocal.simulation import simulate

from conftest import DATA


def tiny_campaign(seed, hold_s=60.0, bias_sd_deg_h=0.05):
    """The tiny scenario at ``seed``: its maneuvers, truth and stated noise."""
    scenario = simulate.load_scenario(DATA / "tiny.yaml")
    scenario["seed"] = seed
    scenario["maneuver_defaults"]["hold_s"] = hold_s
    scenario["gyro"]["bias_sd_deg_h"] = bias_sd_deg_h
    sim, truth = simulate.simulate(scenario)
    stated = {**scenario["star_tracker"], "arw_deg_sqrt_h": scenario["gyro"]["arw_deg_sqrt_h"]}
    return [preprocess.slice_maneuver(sim, m.id) for m in sim.maneuvers], truth, stated


def z_scores(maneuvers, truth, stated, bias):
    table = classic.classic_table(maneuvers, spec.baseline(maneuvers[0].channels), bias, stated)
    truth_values = np.array([truth["parameters"][r.channel][r.parameter] for r in table.itertuples()])
    return ((table["value"] - truth_values) / table["sd"]).to_numpy()


@pytest.mark.full
def test_the_sd_from_holds_matches_the_spread_over_30_simulated_campaigns():
    """z = (classic - truth) / sd over 30 campaigns (720 values): sd 1 within sampling error (about
    0.04 here) where the bias comes from the holds; the paper's trusted bias of 0.05 deg/h is read
    as a scale factor its sd leaves out. Measured: 0.96 and 2.6 (the bias-free variance is right:
    1.01 at zero bias, 0.996 on 100 further campaigns with 400 s holds)."""
    z = {"holds": [], "trusted": []}
    for seed in range(30):
        maneuvers, truth, stated = tiny_campaign(seed, hold_s=120.0)
        for bias in z:
            z[bias].append(z_scores(maneuvers, truth, stated, bias))
    holds, trusted = (np.concatenate(z[b]) for b in ("holds", "trusted"))
    assert len(holds) == 720
    assert 0.88 < holds.std() < 1.12
    assert abs(holds.mean()) < 0.1
    assert trusted.std() > 2.0


def test_auto_takes_the_bias_from_holds_and_every_value_has_an_sd():
    maneuvers, truth, stated = tiny_campaign(3)
    table = classic.classic_table(maneuvers, spec.baseline(maneuvers[0].channels), "auto", stated)
    assert list(table.columns) == classic.TABLE_COLUMNS and len(table) == 24
    assert (table["bias_source"] == "holds").all() and (table["note"] == "").all()
    assert table["maneuvers"].iloc[0] == "yaw_pos:holds"
    assert np.all(np.isfinite(table["sd"])) and np.all(table["sd"] > 0)
    sf = table["parameter"].str.startswith("sf")
    # 60 s holds, 5 arcsec star tracker across, 0.003 deg/sqrt(h): about 35 ppm and 5 arcsec.
    assert 15 < table["sd"][sf].median() < 80 and 2 < table["sd"][~sf].median() < 12
    z = z_scores(maneuvers, truth, stated, "auto")
    assert np.abs(z).max() < 4


def test_short_holds_fall_back_to_the_trusted_bias_with_the_reason():
    maneuvers, _, stated = tiny_campaign(3, hold_s=6.0)
    before, after = classic.hold_windows(maneuvers[0])
    assert classic.MIN_HOLD_SAMPLES <= min(before.sum(), after.sum()) < classic.MIN_BIAS_HOLD_SAMPLES
    table = classic.classic_table(maneuvers, spec.baseline(maneuvers[0].channels), "auto", stated)
    assert len(table) and (table["bias_source"] == "trusted").all()
    assert table["note"].str.contains("bias known before the maneuver is trusted").all()
    assert table["maneuvers"].str.contains(":trusted").all()


def test_without_stated_noise_the_sd_is_missing_and_the_values_unchanged():
    maneuvers, _, stated = tiny_campaign(3)
    base = spec.baseline(maneuvers[0].channels)
    with_sd, without = (classic.classic_table(maneuvers, base, "holds", s) for s in (stated, None))
    assert without["sd"].isna().all()
    assert np.array_equal(with_sd["value"].to_numpy(), without["value"].to_numpy())


def test_an_unknown_bias_choice_is_refused():
    maneuvers, _, _ = tiny_campaign(3)
    with pytest.raises(ValueError, match="bias must be one of"):
        classic.classic(maneuvers[0], "estimated")


def test_solving_again_about_the_estimate_removes_the_second_order_error_of_large_parameters():
    """Truths drawn as the default prior draws them (5000 ppm, 1000 arcsec): the paper's single
    solve, linear about zero, leaves errors of several sd (measured on 8 campaigns: |z| up to 9.4,
    rms 1.46); solved again about its estimate, rms z 0.97 and |z| at most 2.8."""
    z = {1: [], classic.PIPELINE_ITERATIONS: []}
    for seed in range(4):
        scenario = simulate.load_scenario(DATA / "tiny.yaml")
        scenario["seed"] = seed
        simulate.scatter_truth(scenario, np.random.default_rng(seed), 5000.0, 1000.0)
        sim, truth = simulate.simulate(scenario)
        maneuvers = [preprocess.slice_maneuver(sim, m.id) for m in sim.maneuvers]
        stated = {**scenario["star_tracker"], "arw_deg_sqrt_h": scenario["gyro"]["arw_deg_sqrt_h"]}
        for iterations in z:
            table = classic.classic_table(maneuvers, spec.baseline(maneuvers[0].channels), "holds", stated, iterations)
            truth_values = [truth["parameters"][r.channel][r.parameter] for r in table.itertuples()]
            z[iterations].append(((table["value"] - truth_values) / table["sd"]).to_numpy())
    once, again = (np.concatenate(z[k]) for k in z)
    assert np.abs(once).max() > 5
    assert np.sqrt(np.mean(again**2)) < 1.25 and np.abs(again).max() < 4
