"""The sampler on hard posteriors (issue 30): parameters the data do not identify are named before
sampling, and a posterior that cannot converge stops, in bounded time, with the reason."""

import copy
import time
from pathlib import Path

import numpy as np
import pytest

from gyrocal.inference.fit import identification
from gyrocal.inference.fit.likelihood import Stats
from gyrocal.inference.sampling.budget import SamplingBudget, SamplingStopped
from gyrocal.inference.sampling.refusals import EstimateError
from gyrocal.model.spec import baseline
from gyrocal.simulation import simulate

from conftest import DATA

REPOIMU = Path(__file__).resolve().parents[2] / "shared" / "data" / "repoimu"
SAMPLER = {"max_steps": 5000, "min_tau_multiple": 50}


def test_the_budget_stops_once_the_measured_autocorrelation_asks_for_more_steps_than_allowed():
    budget = SamplingBudget(SAMPLER)
    assert budget.stop(150, np.full((4, 27), 99.0)) == ""  # 50 x 99 = 4950 steps: within 5000
    reason = budget.stop(150, np.array([[3.0, 120.0], [np.nan, 2.0]]))
    assert "120 steps" in reason and "6000 steps" in reason and "max_steps = 5000" in reason
    with pytest.raises(SamplingStopped) as stopped:
        budget.check(150, np.array([[3.0, 120.0]]))
    assert stopped.value.tau.shape == (1, 2)


def test_the_budget_stops_after_its_wall_clock_time_unless_converged():
    budget = SamplingBudget({**SAMPLER, "max_seconds": 60})
    budget.started = time.monotonic() - 61
    assert "max_seconds = 60" in budget.stop(300, np.full((4, 27), 20.0))  # 15 tau of the 50 needed
    assert budget.stop(1000, np.full((4, 27), 20.0)) == ""  # 50 tau: converged, nothing to stop
    assert SamplingBudget(SAMPLER).stop(300, np.full((4, 27), 20.0)) == ""  # no time limit given
    assert SamplingBudget({**SAMPLER, "max_seconds": None}).stop(300, np.full((4, 27), 20.0)) == ""  # the default


def test_a_parameter_pinned_only_in_combination_carries_no_information_of_its_own():
    """Parameters 0 and 1 have one column, and parameter 1's prior is 100 times wider: the data pin
    their sum, which parameter 1 carries. Parameter 0's own column carries 50 times its prior's
    information, yet estimated with parameter 1 it carries almost none: a direction only its prior holds."""
    labels = ["a", "b", "c"]
    sd = np.array([1.0, 100.0, 1.0])
    column = np.array([1.0, 1.0, 0.0])
    A = 50.0 * np.outer(column, column) + np.diag([0.0, 0.0, 50.0])
    joint = identification.joint_information(A, sd)
    assert joint[0] < identification.INFORMATION_RATIO_MIN < 0.9 < joint[1]
    assert joint[2] == pytest.approx(50.0)
    held = identification.prior_held_directions(A, sd, labels)
    assert len(held) == 1 and held[0][1][0][0] == "a" and abs(held[0][1][0][1]) > 0.99


def test_uninformed_marks_a_confounded_parameter_one_at_a_time(tiny):
    from gyrocal.io.telemetry import read_campaign
    spec = baseline(read_campaign(tiny[0]).channels)
    info = 1.0 / spec.prior_sd_si**2
    A = np.diag(info * 50.0)
    # two columns that are one: alone, parameter 4's carries 50 times its prior's information, 6's 5e5 times
    scale = np.sqrt(info[[4, 6]] * [50.0, 5e5])
    A[np.ix_([4, 6], [4, 6])] = np.outer(scale, scale)
    flagged = identification.uninformed(Stats(A, np.zeros(len(spec)), 0.0, 0.0, 10), spec)
    assert list(flagged) == [spec.labels[4]]
    assert "only a combination" in flagged[spec.labels[4]] and "its own column: 50" in flagged[spec.labels[4]]


@pytest.fixture(scope="module")
def yaw_only(tmp_path_factory, short_chains):
    """The single-axis campaign through its point estimate."""
    from gyrocal.pipeline.paths import CampaignPaths
    from gyrocal.pipeline.settings import PointEstimateSettings
    from gyrocal.pipeline.steps import classic, point_estimate, preprocess, validate

    out = tmp_path_factory.mktemp("yaw_only")
    simulate.run(DATA / "yaw_only.yaml", out / "sim")
    cfg = copy.deepcopy(short_chains)
    cfg["models"] = {"baseline": ["scale_factor", "misalignment", "bias"]}
    paths = CampaignPaths.under(out / "run")
    paths.mkdirs(["baseline"])
    validate.run(out / "sim" / "campaign", paths.input_json, None, cfg["sampler"]["block_s"])
    ids = preprocess.run(out / "sim" / "campaign", paths.input_json, paths.preprocess, False)
    classic.run(paths.maneuvers(ids), paths.input_json, paths.classic, cfg["noise"])
    point_estimate.run(paths.maneuvers(ids), paths.input_json, paths.model("baseline").point_estimate, "baseline",
                       PointEstimateSettings.of(cfg, "baseline"))
    return paths, ids, cfg


def test_a_single_axis_posterior_that_cannot_converge_in_budget_stops_at_once_with_why(yaw_only):
    from gyrocal.pipeline.settings import PosteriorSettings
    from gyrocal.pipeline.steps import posterior

    paths, ids, cfg = yaw_only
    cfg = copy.deepcopy(cfg)
    cfg["sampler"].update(min_tau_multiple=1000, max_steps=100)  # 1000 tau cannot fit in 100 steps
    start = time.monotonic()
    with pytest.raises(EstimateError) as refused:
        posterior.run(paths.maneuvers(ids), paths.model("baseline").point_estimate,
                    paths.model("baseline"), PosteriorSettings.of(cfg))
    assert time.monotonic() - start < 60
    message = str(refused.value)
    assert "stopped without converging" in message and "beyond sampler.max_steps = 100" in message
    assert "Slowest: " in message and "What the data leave weak: nothing stands out" in message
    assert not Path(paths.model("baseline").posterior).exists()


def run_posterior(campaign_dir, out, cfg):
    """Validate, preprocess and fit the baseline model of ``campaign_dir``, then sample its posterior;
    the sampler's record, or the refusal."""
    import json

    from gyrocal.pipeline.paths import CampaignPaths
    from gyrocal.pipeline.settings import PointEstimateSettings, PosteriorSettings
    from gyrocal.pipeline.steps import classic, point_estimate, posterior, preprocess, validate

    paths = CampaignPaths.under(out)
    paths.mkdirs(["baseline"])
    validate.run(campaign_dir, paths.input_json, None, cfg["sampler"]["block_s"])
    ids = preprocess.run(campaign_dir, paths.input_json, paths.preprocess, False)
    classic.run(paths.maneuvers(ids), paths.input_json, paths.classic, cfg["noise"])
    point_estimate.run(paths.maneuvers(ids), paths.input_json, paths.model("baseline").point_estimate, "baseline",
                       PointEstimateSettings.of(cfg, "baseline"))
    try:
        posterior.run(paths.maneuvers(ids), paths.model("baseline").point_estimate,
                    paths.model("baseline"), PosteriorSettings.of(cfg))
    except EstimateError as refused:
        return str(refused)
    return json.loads(Path(paths.model("baseline").sampler).read_text())


@pytest.mark.full
def test_a_single_axis_campaign_converges_with_the_default_settings_within_the_step_budget(tmp_path, config):
    simulate.run(DATA / "yaw_only.yaml", tmp_path / "sim")
    cfg = copy.deepcopy(config)
    cfg["models"] = {"baseline": ["scale_factor", "misalignment", "bias"]}
    record = run_posterior(tmp_path / "sim" / "campaign", tmp_path / "run", cfg)
    assert isinstance(record, dict) and record["converged"], record
    assert record["steps"] <= cfg["sampler"]["max_steps"]


@pytest.mark.full
@pytest.mark.skipif(not (REPOIMU / "TStick_Test04_Trial1.csv").is_file(),
                    reason="the shared RepoIMU recordings (../shared/data/repoimu) are not here")
def test_the_repoimu_z_trial_converges_or_stops_with_why_within_the_step_budget(tmp_path, config):
    import yaml

    from gyrocal.io import importer
    importer.import_files("repoimu", tmp_path / "z", [REPOIMU / "TStick_Test04_Trial1.csv"], 1.0)
    cfg = copy.deepcopy(config)
    tstick = yaml.safe_load((Path(__file__).resolve().parents[1] / "config" / "tstick.yaml").read_text())
    for key in ("noise", "priors"):
        cfg[key] = {**cfg[key], **tstick[key]}
    cfg["models"] = {"baseline": ["scale_factor", "misalignment", "bias"]}
    record = run_posterior(tmp_path / "z", tmp_path / "run", cfg)
    if isinstance(record, str):
        assert "Slowest:" in record or "do not identify" in record, record
    else:
        assert record["converged"] and record["steps"] <= cfg["sampler"]["max_steps"], record


def test_a_gauss_markov_share_fitted_at_its_bound_is_named_with_what_to_do():
    """At 100 Hz the REML puts RepoIMU's reference noise all in the Gauss-Markov part (share 0.9997): the
    stop names it and the longer reference interval; inside the bounds, or with white noise, nothing."""
    from gyrocal.inference.fit.noisefit import GM_LOGIT_BOUND
    from gyrocal.inference.sampling.refusals import share_at_bound

    at_top = np.log([1e-3, 1e-3, 1e-5, 1.0, 0.65])
    at_top[3] = GM_LOGIT_BOUND - 0.01
    note = share_at_bound(at_top)
    assert "share 0.9997" in note and "tau 0.65 s" in note and "--reference-interval" in note
    at_top[3] = -at_top[3]
    assert "fits as white" in share_at_bound(at_top) and "share 0.00034" in share_at_bound(at_top)
    at_top[3] = GM_LOGIT_BOUND - 0.5
    assert share_at_bound(at_top) == ""
    assert share_at_bound(np.log([1e-3, 1e-3, 1e-5])) == ""
