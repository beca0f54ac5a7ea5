"""Prior-data conflict: the likelihood in its prior's tail is found, said, and blocks a GO."""

import json

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from gyrocal.criticism import priorconflict, verdict
from gyrocal.finding import Status
from gyrocal.io.telemetry import write_campaign
from gyrocal.model import effects
from gyrocal.model.channels import Channel
from gyrocal.model.spec import ModelSpec
from gyrocal.simulation import simulate

from conftest import DATA, config_with, run_campaign

CHANNELS = (Channel("gx", None, "roll"), Channel("gy", None, "pitch"), Channel("gz", None, "yaw"))
DRIFT_MODEL = list(effects.BASELINE) + ["bias_drift"]


def drift_spec():
    return ModelSpec.build("bias_drift", effects.resolve("bias_drift", DRIFT_MODEL, {}), CHANNELS)


def table_of(spec, lik, lik_sd, posterior_mean):
    """`conflict_table` of a spec whose every parameter the data say ``lik +- lik_sd`` (units)."""
    theta = spec.to_si(np.asarray(lik, dtype=float))
    cov = np.diag(spec.to_si(np.asarray(lik_sd, dtype=float)) ** 2)
    calibration = pd.DataFrame({"channel": [p.owner for p in spec.parameters],
                                "parameter": [p.name for p in spec.parameters], "mean": posterior_mean})
    return priorconflict.conflict_table(spec, theta, cov, calibration)


def test_the_issues_drift_is_a_conflict_that_blocks_a_go():
    """The issue's campaign: the data say -2.10 deg/h/h (sd 0.375), the prior 0 +- 0.5, the
    posterior -1.30: z = -2.10 / sqrt(0.5^2 + 0.375^2) = -3.36, pulled 2.1 of the data's sd."""
    spec = drift_spec()
    n = len(spec)
    lik, lik_sd, mean = np.full(n, 100.0), np.full(n, 20.0), np.full(n, 100.0)
    drift = [i for i, p in enumerate(spec.parameters) if p.effect == "bias_drift"]
    lik[drift], lik_sd[drift], mean[drift] = -2.10, 0.375, -1.30
    table = table_of(spec, lik, lik_sd, mean)
    row = table.set_index("label").loc["gz.bias_drift"]
    assert row["z"] == pytest.approx(-2.10 / np.hypot(0.5, 0.375))
    assert row["shift_lik_sd"] == pytest.approx(0.8 / 0.375)
    assert row["tail_p"] == pytest.approx(2 * stats.t.sf(2.10 / np.hypot(0.5, 0.375), 4))  # the Student-t prior's
    assert table["conflict"].sum() == 3 and not table["conflict"][table["core"]].any()
    finding = priorconflict.conflict_check(table)
    assert finding.status is Status.REFUSE and finding.figure == pytest.approx(3.36, abs=0.01)
    assert "gz.bias_drift: the data say -2.1 +- 0.38 deg/h/h, 3.4 sd into the tail of its prior 0 +- 0.5" in finding.why
    assert finding.action == "widen the prior in the config and rerun: priors: {sd: {bias_drift.bias_drift: 2.9}}"
    assert verdict.verdict("c", "bias_drift", [finding])["verdict"] == "NO-GO"


def test_a_conflict_the_prior_barely_moves_warns_unless_core():
    spec = drift_spec()
    n = len(spec)
    lik, lik_sd = np.zeros(n), np.full(n, 1.0)
    drift = [i for i, p in enumerate(spec.parameters) if p.effect == "bias_drift"]
    lik[drift[0]], lik_sd[drift] = 3.0, 0.05                       # well determined: prior moves it 0.01 sd
    finding = priorconflict.conflict_check(table_of(spec, lik, lik_sd, lik - 0.0005 * np.isin(np.arange(n), drift)))
    assert finding.status is Status.WARN and finding.passed and finding.where == "gx.bias_drift"
    lik[0] = 16000.0                                               # gx.sf_pos 3.2 prior sd out: core
    finding = priorconflict.conflict_check(table_of(spec, lik, lik_sd, lik))
    assert finding.status is Status.REFUSE and "priors: {sf_sd_ppm: 16000}" in finding.action


def test_estimates_inside_their_priors_raise_no_conflict():
    spec = drift_spec()
    n = len(spec)
    rng = np.random.default_rng(1)
    sd = np.array([p.prior_sd for p in spec.parameters])
    lik = rng.normal(0.0, 1.0, n) * sd
    finding = priorconflict.conflict_check(table_of(spec, lik, 0.1 * sd, lik))
    assert finding.status is Status.PASS and finding.figure < priorconflict.Z_MAX


@pytest.fixture(scope="module")
def drift_run(tmp_path_factory, short_chains):
    """The tiny campaign with a bias drift of 2 deg/h/h on every channel, through every step with
    the drift model only (so that it is the one reviewed), short chains."""
    out = tmp_path_factory.mktemp("drift")
    scenario = simulate.load_scenario(DATA / "tiny.yaml")
    scenario["effects"]["bias_drift_deg_h_per_h"] = 2.0
    campaign, _ = simulate.simulate(scenario)
    write_campaign(campaign, out / "campaign")
    run_campaign(out / "campaign", out / "run", config_with(short_chains, {"bias_drift": DRIFT_MODEL}),
                 models=("bias_drift",))
    return out / "run"


@pytest.mark.full
def test_a_2_deg_h_h_drift_is_flagged_and_the_verdict_is_not_go(drift_run):
    """The drift model's estimate of about 2 deg/h/h (sd 0.22-0.48 on this campaign) lies beyond
    3 sd of the default prior 0 +- 0.5 on at least one channel."""
    doc = json.loads((drift_run / "verdict.json").read_text())
    check = next(c for c in doc["checks"] if c["check"] == priorconflict.CHECK)
    assert not check["passed"] and doc["verdict"] == "NO-GO"
    assert "bias_drift" in check["why"] and "into the tail of its prior 0 +- 0.5" in check["why"]


def test_a_clean_campaign_raises_no_conflict(tiny_run):
    out, _ = tiny_run
    doc = json.loads((out / "verdict.json").read_text())
    check = next(c for c in doc["checks"] if c["check"] == priorconflict.CHECK)
    assert check["passed"] and check["why"].startswith("every parameter's estimate lies within 3 sd")
