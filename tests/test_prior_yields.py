"""The effects' Student-t prior yields to the data (issue 43): a bias ramp four prior scales out,
simulated and fitted with the sampler, is believed, where a normal prior pulled it toward zero."""

import copy

import numpy as np
import pandas as pd
import pytest
import yaml

from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.model.effects import BiasDrift
from gyrocal.pipeline import run
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.simulation import simulate

from conftest import DATA

DRIFT_DEG_H_H = 2.0
"""The simulated ramp: four times the drift prior's scale (`BiasDrift`, 0.5 deg/h/h)."""


@pytest.fixture(scope="module")
def drift_run(tmp_path_factory, short_chains):
    """The tiny campaign with a 2 deg/h/h ramp on every channel and 240-s holds (the ramp's likelihood
    sd about a tenth of the prior's scale), through the drift model's posterior."""
    out = tmp_path_factory.mktemp("drift")
    scenario = yaml.safe_load((DATA / "tiny.yaml").read_text())
    scenario["effects"] = {"bias_drift_deg_h_per_h": DRIFT_DEG_H_H}
    scenario["maneuver_defaults"]["hold_s"] = 240.0
    (out / "scenario.yaml").write_text(yaml.safe_dump(scenario))
    simulate.run(out / "scenario.yaml", out)
    cfg = copy.deepcopy(short_chains)
    cfg["models"] = {"drift": ["scale_factor", "misalignment", "bias", "bias_drift"]}
    paths = CampaignPaths.under(out / "results")
    run.calibrate_campaign(out / "campaign", paths, cfg, ["drift"], figures=False, through="posterior", strict=True)
    return paths.model("drift")


@pytest.mark.full  # 7 s; the fast tier keeps the Student-t priors' unit tests (test_priorfamily, test_prior_pull)
def test_a_ramp_four_prior_scales_out_keeps_the_likelihoods_mean_and_its_intervals_cover(drift_run):
    est = PointEstimate.load(drift_run.point_estimate, linearizations=False)
    rows = [i for i, p in enumerate(est.spec.parameters) if p.name == "bias_drift"]
    scale = BiasDrift.parameters[0].prior_sd
    unit = est.spec.parameters[rows[0]].si_per_unit
    lik, lik_sd = est.theta[rows] / unit, np.sqrt(np.diag(est.cov))[rows] / unit
    assert np.all(np.abs(lik - DRIFT_DEG_H_H) < 3 * lik_sd) and np.all(lik_sd < scale / 4)
    assert np.all(lik / scale > 3.5)   # the data say: about four prior scales out
    summary = pd.read_csv(drift_run.summary).set_index("label").loc[[est.spec.labels[i] for i in rows]]
    shift = (summary["mean"].to_numpy() - lik) / lik_sd
    # a normal prior of sd 0.5 would pull each by lik * lik_sd / (scale^2 + lik_sd^2) of its sd
    normal_pull = lik * lik_sd / (scale**2 + lik_sd**2)
    assert np.all(np.abs(shift) < 0.5) and np.mean(np.abs(shift)) < 0.6 * np.mean(normal_pull)
    assert np.all((summary["ci95_low"] <= DRIFT_DEG_H_H) & (summary["ci95_high"] >= DRIFT_DEG_H_H))
