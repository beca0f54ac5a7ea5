"""Several campaigns of one unit: the multivariate consistency test and the joint fit
(gyrocal.criticism.consistency, .joint; `gyrocal joint`)."""

import copy
import json

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from scipy.spatial.transform import Rotation

from gyrocal.criticism.consistency import consistency, pair_test, posterior_of
from gyrocal.criticism.joint import CampaignLikelihood, joint_fit
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.io.calibration import COLUMNS
from gyrocal.io.scenario import load_scenario
from gyrocal.io.telemetry import write_campaign
from gyrocal.pipeline import cli
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.run import calibrate_campaign
from gyrocal.simulation.simulate import simulate

from conftest import DATA


def _spd(rng, n, scale):
    m = rng.standard_normal((n, n))
    return scale * (m @ m.T + n * np.eye(n))


def test_the_chi2_of_two_campaigns_is_the_dense_formula_with_both_covariances():
    """d' (C_A + C_B)^-1 d, by numpy's dense inverse, on a 5-parameter case the data inform well
    (a prior 10^4 times wider than the data: the posteriors are the likelihoods)."""
    rng = np.random.default_rng(3)
    info_a, info_b = _spd(rng, 5, 50.0), _spd(rng, 5, 80.0)
    x_a, x_b = rng.standard_normal(5) * 0.3, rng.standard_normal(5) * 0.3
    d = x_b - x_a
    dense = d @ np.linalg.inv(np.linalg.inv(info_a) + np.linalg.inv(info_b)) @ d
    test = consistency([x_a, x_b], [info_a, info_b], np.zeros(5), np.full(5, 1e4), list("abcde"))
    assert test.chi2 == pytest.approx(dense, rel=1e-6) and test.dof == 5
    assert test.p_value == pytest.approx(stats.chi2.sf(dense, 5), rel=1e-6)
    assert sum(d.chi2 for d in test.against_rest[0]["directions"]) < dense  # the three largest of five
    pair = pair_test(x_a, np.linalg.inv(info_a), x_b, np.linalg.inv(info_b), np.full(5, 1e4), list("abcde"), top=5)
    assert sum(d.chi2 for d in pair["directions"]) == pytest.approx(dense, rel=1e-9)


def test_a_parameter_prior_only_in_one_campaign_drops_out_with_its_degree_of_freedom():
    """Campaign B says nothing about the last parameter (no information there): its difference
    leaves the test, and the test has one degree of freedom less; the rest is the dense formula
    over the first three parameters with the posteriors' means and covariances."""
    rng = np.random.default_rng(4)
    info_a, info_b = _spd(rng, 4, 40.0), _spd(rng, 4, 40.0)
    info_b[3, :] = info_b[:, 3] = 0.0
    x_a, x_b = np.zeros(4), np.array([0.05, -0.1, 0.05, np.nan])
    test = consistency([x_a, x_b], [info_a, info_b], np.zeros(4), np.ones(4), list("abcd"))
    (m_a, c_a), (m_b, c_b) = (posterior_of(x, i, np.zeros(4), np.ones(4)) for x, i in ((x_a, info_a), (x_b, info_b)))
    sub = np.ix_(range(3), range(3))
    d = (m_b - m_a)[:3]
    assert test.dof == 3
    assert test.chi2 == pytest.approx(d @ np.linalg.inv(c_a[sub] + c_b[sub]) @ d, rel=1e-3)


def test_directions_the_data_tell_less_than_nine_priors_are_left_out():
    """Information 5 prior units along one direction (the posteriors keep 1/6 of the prior's
    variance, above 0.1): not counted, where 20 prior units is."""
    prior_sd = np.array([2.0, 3.0])
    for weak, dof in ((5.0, 1), (20.0, 2)):
        info = np.diag([100.0, weak]) / np.outer(prior_sd, prior_sd)
        assert consistency([np.zeros(2), np.ones(2)], [info, info], np.zeros(2), prior_sd, ["a", "b"]).dof == dof


def test_three_consistent_campaigns_each_against_the_others_hold_their_level():
    """400 simulated triples of estimates with known information: each campaign's test against the
    other two has its chi-square's mean (4, se 0.3) and level (5 %, se 1.1 %); the verdict over the
    three (Bonferroni) fires at most at the stated 5 %."""
    rng = np.random.default_rng(5)
    infos = [_spd(rng, 4, s) for s in (20.0, 50.0, 90.0)]
    chols = [np.linalg.cholesky(np.linalg.inv(i)) for i in infos]
    values = [consistency([c @ rng.standard_normal(4) for c in chols], infos, np.zeros(4), np.full(4, 1e4),
                          list("abcd")) for _ in range(400)]
    each = [t for v in values for t in v.against_rest]
    assert {t["dof"] for t in each} == {4}
    assert np.mean([t["chi2"] for t in each]) == pytest.approx(4.0, abs=0.4)
    assert np.mean([t["p_value"] < 0.05 for t in each]) == pytest.approx(0.05, abs=0.02)
    assert np.mean([not v.consistent(0.05) for v in values]) <= 0.05 + 0.02


def test_the_joint_fit_of_two_equal_campaigns_narrows_by_root_two_and_averages_them():
    rng = np.random.default_rng(6)
    info = _spd(rng, 3, 1e4)
    liks = [CampaignLikelihood(k, list("abc"), x, info) for k, x in (("a", np.array([1.0, 2.0, 3.0])),
                                                                     ("b", np.array([1.2, 1.8, 3.1])))]
    one, two = joint_fit(liks[:1], np.zeros(3), np.full(3, 1e3)), joint_fit(liks, np.zeros(3), np.full(3, 1e3))
    assert two.sd / one.sd == pytest.approx(np.full(3, 2**-0.5), rel=1e-6)
    assert two.point == pytest.approx([1.1, 1.9, 3.05], abs=1e-9)


def test_a_likelihood_turned_into_another_frame_and_back_is_itself():
    """A baseline spec of three single-axis channels; 0.3 deg about yaw there and back."""
    from gyrocal.model.channels import Channel
    from gyrocal.model.spec import baseline
    spec = baseline([Channel("gyro_x", None, "roll"), Channel("gyro_y", None, "pitch"), Channel("gyro_z", None, "yaw")])
    rng = np.random.default_rng(7)
    units = spec.si_per_unit[spec.core]
    x = rng.standard_normal(len(units)) * 200.0 * units
    info = _spd(rng, len(units), 1.0) / np.outer(units, units) / 1e4
    lik = CampaignLikelihood("a", list(spec.labels), x, info)
    turn = Rotation.from_rotvec(np.deg2rad([0.0, 0.0, 0.3]))
    there = lik.turned(spec, turn)
    back = there.turned(spec, turn.inv())
    assert np.abs(there.estimate - x).max() / units.max() > 100  # it moved (arcsec/ppm)
    assert back.estimate / units == pytest.approx(x / units, abs=1e-6)
    assert back.info == pytest.approx(info, rel=1e-4)  # the Jacobians are taken at two points


def _point_estimate_run(tmp_path_factory, name, scenario, seed, cfg):
    root = tmp_path_factory.mktemp(name)
    campaign, _ = simulate(scenario, seed)
    write_campaign(campaign, root / "campaign")
    paths = CampaignPaths.under(root / "run")
    calibrate_campaign(root / "campaign", paths, cfg, ["baseline"], figures=False, through="point_estimate")
    return paths.root


SHIFTED = "dtg2_yaw.mis_roll"


@pytest.fixture(scope="module")
def three_runs(tmp_path_factory, config):
    """The tiny campaign of one truth at two seeds, and at the second seed with dtg2_yaw's
    misalignment toward roll 30 arcsec off (about 5 of one campaign's sd)."""
    scenario = load_scenario(DATA / "tiny.yaml")
    moved = copy.deepcopy(scenario)
    moved["truth"]["dtg2_yaw"]["mis_roll"] += 30.0
    return [_point_estimate_run(tmp_path_factory, n, s, seed, config)
            for n, s, seed in (("a", scenario, 21), ("b", scenario, 22), ("c", moved, 22))]


def test_two_campaigns_of_one_truth_are_consistent_and_a_moved_parameter_is_found(three_runs, tmp_path, capsys):
    a, b, c = three_runs
    assert cli.main(["joint", a, b, "--out", str(tmp_path / "ab")]) == 0
    same = json.loads((tmp_path / "ab" / "consistency.json").read_text())
    assert same["dof"] == 24 and 0.01 < same["p_value"] < 0.99
    assert "VERDICT: CONSISTENT" in capsys.readouterr().out
    assert cli.main(["joint", a, c, "--out", str(tmp_path / "ac")]) == 1
    moved = json.loads((tmp_path / "ac" / "consistency.json").read_text())
    assert moved["p_value"] < 1e-4 and "VERDICT: INCONSISTENT" in capsys.readouterr().out
    top = moved["against_rest"][0]["directions"][0]["loadings"]
    assert SHIFTED in top and abs(top[SHIFTED]) == max(abs(w) for w in top.values())


def test_the_joint_calibration_has_the_contracts_columns_and_one_campaigns_sd_over_root_two(three_runs, tmp_path):
    a, b, _ = three_runs
    assert cli.main(["joint", a, b, "--out", str(tmp_path)]) == 0
    table = pd.read_csv(tmp_path / "calibration.csv")
    assert list(table.columns) == COLUMNS and len(table) == 24 and not table["prior_only"].any()
    single = PointEstimate.load(CampaignPaths.under(a).model("baseline").point_estimate)
    sd_one = np.sqrt(np.diag(single.cov)) / single.spec.si_per_unit
    assert table["sd"].to_numpy() / sd_one == pytest.approx(np.full(24, 2**-0.5), rel=0.05)
    assert table["ci95_high"].to_numpy() - table["mean"].to_numpy() == pytest.approx(1.96 * table["sd"], rel=1e-3)


def test_joint_names_a_run_without_a_point_estimate(tmp_path, capsys):
    assert cli.main(["joint", str(tmp_path / "x"), str(tmp_path / "y"), "--out", str(tmp_path / "o")]) == 2
    assert "no point estimate of model 'baseline'" in capsys.readouterr().err


def test_a_campaigns_own_effects_are_integrated_out_under_their_prior():
    """A model with bias drift: the channel parameters' information is the inverse of the core block
    of the covariance with the drift's prior added (numpy's dense inverse), and a prior-only
    parameter has none."""
    from gyrocal.model import effects as fx
    from gyrocal.model.channels import Channel
    from gyrocal.model.spec import ModelSpec
    channels = [Channel("gyro_x", None, "roll"), Channel("gyro_y", None, "pitch"), Channel("gyro_z", None, "yaw")]
    spec = ModelSpec.build("drift", fx.resolve("drift", fx.BASELINE + ("bias_drift",), {}), channels)
    spec = spec.with_prior_only({"gyro_z.sf_neg": "no -yaw maneuver"})
    free = spec.free
    rng = np.random.default_rng(8)
    units = spec.si_per_unit
    cov = np.full((len(spec), len(spec)), np.nan)
    cov[np.ix_(free, free)] = np.linalg.inv(_spd(rng, int(free.sum()), 1.0)) * np.outer(units, units)[np.ix_(free, free)]
    theta = rng.standard_normal(len(spec)) * units
    lik = CampaignLikelihood.of("a", spec, theta, cov, spec.prior_mean_si, spec.prior_sd_si)
    prec = np.where(np.arange(len(spec)) >= spec.n_core, 1.0 / spec.prior_sd_si**2, 0.0)[free]
    dense = np.linalg.inv(np.linalg.inv(cov[np.ix_(free, free)]) + np.diag(prec))
    core_free = free[spec.core]
    reference = np.linalg.inv(dense[:core_free.sum(), :core_free.sum()])
    assert lik.info[np.ix_(core_free, core_free)] == pytest.approx(reference, rel=1e-8)
    assert not lik.free[spec.index("gyro_z.sf_neg")] and np.all(lik.info[spec.index("gyro_z.sf_neg")] == 0)
    assert len(lik.labels) == spec.n_core == 12
