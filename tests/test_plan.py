"""`gyrocal plan`: what a planned campaign predicts, against the pipeline's own estimates and tests."""

import copy
import dataclasses

import numpy as np
import pandas as pd
import pytest
import yaml

from gyrocal.criticism import diagnostics
from gyrocal.inference.fit.estimate import point_estimate, wls
from gyrocal.inference.fit.likelihood import Stats
from gyrocal.inference.noise import covariance
from gyrocal.maneuvers import preprocess
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec, baseline
from gyrocal.pipeline import cli
from gyrocal.planning import plan
from gyrocal.simulation import simulate

from conftest import DATA, ROOT, truth_vector

CONFIG = ROOT / "config" / "config.yaml"


@pytest.fixture(scope="module")
def cfg():
    return plan.read_config(CONFIG)


def test_predicted_crlb_equals_the_wls_sd_of_a_simulated_campaign_of_the_same_plan(cfg):
    """The plan's Cramér-Rao bound is the WLS sd the point estimate reports on noisy data of the
    same plan (stated noise, no REML), although the plan never draws noise."""
    scenario = simulate.load_scenario(DATA / "tiny.yaml")
    predicted = plan.plan(scenario, cfg)
    campaign, truth = simulate.simulate(scenario)
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    spec = baseline(campaign.channels)
    stated = plan.stated_noise(scenario, cfg["noise"])
    theta0 = spec.core_vector(truth_vector(campaign.channels, truth))
    est = point_estimate(maneuvers, spec, stated, theta0, estimate_scales=False)
    assert predicted.spec.labels == est.spec.labels
    wls_sd = np.sqrt(np.diag(est.cov))
    np.testing.assert_allclose(predicted.crlb_sd, wls_sd, rtol=0.02)
    # the prior (5000 ppm, 1000 arcsec) barely narrows what the data say
    np.testing.assert_allclose(np.sqrt(np.diag(predicted.cov)), predicted.crlb_sd, rtol=1e-3)


def gauss_markov_tiny(tau_s=30.0, hold_s=60.0, gm_arcsec=(5.0, 20.0)):
    """tiny.yaml's campaign with a Gauss-Markov part (``gm_arcsec`` across and about the boresight; by
    default as large as its white noise, 5 / 20 arcsec) over ``tau_s``, as the verdict battery's
    Gauss-Markov kinds fly it."""
    scenario = simulate.load_scenario(DATA / "tiny.yaml")
    scenario["star_tracker"].update(gm_sigma_cross_arcsec=gm_arcsec[0], gm_sigma_about_arcsec=gm_arcsec[1],
                                    gm_tau_s=tau_s)
    scenario["maneuver_defaults"]["hold_s"] = hold_s
    return scenario


def test_with_gauss_markov_reference_noise_the_crlb_is_the_correlated_models_wls_sd(cfg):
    """A star tracker with a Gauss-Markov part as large as its white one: the plan's bound is the WLS sd
    of the model with st_correlated_noise at that noise (each sd the parts' total, half of it
    Gauss-Markov, tau 30 s) on noisy data of the plan, and twice to five times the white plan's, as the
    battery's posteriors are."""
    scenario = gauss_markov_tiny()
    predicted = plan.plan(scenario, cfg)
    stated = plan.stated_noise(scenario, cfg["noise"])
    assert "; Gauss-Markov 5 / 20 arcsec over 30 s;" in plan.report([predicted])
    campaign, truth = simulate.simulate(scenario)
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    names = ["scale_factor", "misalignment", "bias", "st_correlated_noise"]
    spec = ModelSpec.build("correlated", effects.resolve("correlated", names, {}), campaign.channels)
    theta0 = spec.core_vector(truth_vector(campaign.channels, truth))
    total = {**stated, "sigma_cross_arcsec": np.sqrt(50.0), "sigma_about_arcsec": np.sqrt(800.0),
             "st_gm_fraction": 0.5, "st_gm_tau_s": 30.0}
    log_sigma = covariance.log_sigma_of(total, correlated=True)  # the stated noise: the WLS alone, no REML
    est = wls(maneuvers, spec, total, log_sigma, theta0, correlation_time_s=30.0)
    np.testing.assert_allclose(predicted.crlb_sd, np.sqrt(np.diag(est.cov)), rtol=0.02)
    white = plan.plan(simulate.load_scenario(DATA / "tiny.yaml"), cfg)
    assert np.all((predicted.crlb_sd > 2 * white.crlb_sd) & (predicted.crlb_sd < 5 * white.crlb_sd))


def test_a_gauss_markov_part_on_one_axis_is_planned_on_that_axis_alone(cfg):
    """Gauss-Markov noise across the boresight only, or about it only, enters as that axis's variance
    (not one share of the total for both), and each bound lies between the white plan's and the plan
    with both (a covariance component added never adds information)."""
    tau_s, variances = plan.noise_variances(plan.stated_noise(gauss_markov_tiny(gm_arcsec=(5.0, 0.0)), cfg["noise"]))
    assert tau_s == 30.0 and variances["gm_about"] == 0.0
    assert variances["gm_cross"] == pytest.approx(np.deg2rad(5.0 / 3600.0) ** 2, rel=1e-12)
    assert variances["cross"] == pytest.approx(np.deg2rad(5.0 / 3600.0) ** 2, rel=1e-12)
    white = plan.plan(simulate.load_scenario(DATA / "tiny.yaml"), cfg).crlb_sd
    both = plan.plan(gauss_markov_tiny(), cfg).crlb_sd
    for one_axis in ((5.0, 0.0), (0.0, 20.0)):
        sd = plan.plan(gauss_markov_tiny(gm_arcsec=one_axis), cfg).crlb_sd
        assert np.all((sd >= white * (1 - 1e-9)) & (sd <= both * (1 + 1e-9))) and np.any(sd > 1.05 * white)


def test_longer_holds_narrow_what_gauss_markov_noise_widens_and_the_plan_flies_no_noise(cfg):
    """Holds ten correlation times long give the bound back much of what tau = 30 s takes; the plan's
    trajectory is the same with the Gauss-Markov part as without: its reference carries none of it."""
    short, long = (plan.plan(gauss_markov_tiny(hold_s=h), cfg).crlb_sd for h in (60.0, 300.0))
    assert np.all(long < 0.5 * short)
    with_gm = plan.planned_maneuvers(gauss_markov_tiny())
    without = plan.planned_maneuvers(simulate.load_scenario(DATA / "tiny.yaml"))
    for a, b in zip(with_gm, without):
        np.testing.assert_array_equal(a.st_quat, b.st_quat)


def test_one_rate_per_direction_cannot_detect_a_rate_squared_scale_factor_two_rates_can(cfg):
    """onerate_nonlinearity.yaml hides 8000 ppm/(deg/s)^2 behind one rate per direction: the plan says no
    test can see it (the scale factor takes it); a second rate per direction makes it detectable."""
    one = simulate.load_scenario(DATA / "onerate_nonlinearity.yaml")
    two = copy.deepcopy(one)
    two["maneuvers"] += [{**m, "id": f"{m['id']}_slow", "rate_deg_s": 0.25} for m in one["maneuvers"]]
    row = {name: p.detection.set_index("effect").loc["sf_nonlinearity"]
           for name, p in (("one", plan.plan(one, cfg)), ("two", plan.plan(two, cfg)))}
    assert not row["one"]["detectable"]
    assert row["one"]["tested_directions"] == 0
    assert "scale_factor" in row["one"]["why_not"]
    assert row["two"]["detectable"]
    assert row["two"]["tested_directions"] == 6
    assert row["two"]["unit"] == "ppm/(deg/s)^2"
    assert 100 < row["two"]["detectable_magnitude"] < 8000


def test_noncentrality_equals_the_structure_tests_drop_on_noise_free_data_carrying_the_effect():
    """On data with no noise and the effect at magnitude delta, the diagnostics' score statistic is
    exactly the noncentrality; a candidate the model's columns span is not tested (0 directions)."""
    rng = np.random.default_rng(3)
    X = rng.normal(size=(40, 6))
    X[:, 5] = X[:, 0] - 2 * X[:, 1] + 1e-6 * rng.normal(size=40)   # spanned by the model's columns
    A = X.T @ X
    base, cand = [0, 1, 2], [3, 4, 5]
    delta = np.array([0.7, -0.4, 0.0])
    b = A[:, cand] @ delta
    drop = diagnostics.conditional_drop(Stats(A, b, float(delta @ A[np.ix_(cand, cand)] @ delta), 0.0, 40), base, cand)
    lam, df = plan.noncentrality(A, base, cand, delta)
    assert df == 2
    assert lam == pytest.approx(drop, rel=1e-9)
    assert plan.noncentrality(A, base, [5], [1.0]) == (0.0, 0)


def test_detectable_noncentrality_of_one_column_at_p_1e_minus_6_is_the_normal_quantiles_sum_squared():
    """One column, p = 1e-6, power 0.9: sqrt(lambda) = z(1 - 0.5e-6) + z(0.9) = 4.8916 + 1.2816."""
    assert np.sqrt(plan.detectable_noncentrality(1, 1, -6.0)) == pytest.approx(4.8916 + 1.2816, abs=2e-3)


def test_a_direction_never_flown_leaves_its_scale_factors_at_their_prior(cfg):
    scenario = simulate.load_scenario(DATA / "tiny.yaml")
    scenario["maneuvers"] = [m for m in scenario["maneuvers"] if m["id"] != "pitch_neg"]
    table = plan.plan(scenario, cfg).table().set_index(["channel", "parameter"])
    for channel in ("dtg1_pitch", "dtg2_pitch"):
        assert table.loc[(channel, "sf_neg"), "prior_only"] == "no -pitch turn in the data: turn about -pitch"
        assert table.loc[(channel, "sf_neg"), "predicted_sd"] == pytest.approx(5000.0)
        assert table.loc[(channel, "sf_pos"), "predicted_sd"] < 100.0


def test_a_plan_predicts_the_combinations_as_sqrt_a_c_a_and_says_one_direction_does_not_resolve_them(cfg):
    """Without the -pitch maneuver sf_neg sits at its prior, so neither sf_mean nor sf_asym of a pitch
    channel is resolved (ratio near 1/sqrt(2)); roll's both are, and their sd is sqrt(a' C a)."""
    scenario = simulate.load_scenario(DATA / "tiny.yaml")
    scenario["maneuvers"] = [m for m in scenario["maneuvers"] if m["id"] != "pitch_neg"]
    p = plan.plan(scenario, cfg)
    table = p.table().set_index(["channel", "parameter"])
    pos, neg = p.spec.index("dtg1_roll.sf_pos"), p.spec.index("dtg1_roll.sf_neg")
    c = p.cov[np.ix_([pos, neg], [pos, neg])] / 1e-12
    assert table.loc[("dtg1_roll", "sf_mean"), "predicted_sd"] == pytest.approx(np.sqrt(c.sum() / 4), rel=1e-9)
    assert table.loc[("dtg1_roll", "sf_asym"), "predicted_sd"] == pytest.approx(
        np.sqrt(c[0, 0] + c[1, 1] - 2 * c[0, 1]), rel=1e-9)
    assert table.loc[("dtg1_roll", "sf_mean"), "resolved"] and table.loc[("dtg1_roll", "sf_asym"), "resolved"]
    for name in ("sf_mean", "sf_asym"):
        row = table.loc[("dtg1_pitch", name)]
        assert not row["resolved"] and row["sd_over_prior"] == pytest.approx(np.sqrt(0.5), abs=0.01)
        assert np.isinf(row["crlb_sd"])


def test_a_plan_says_an_estimated_mounting_would_take_up_each_axis_rotation_of_the_triad(cfg):
    table = plan.plan(simulate.load_scenario(DATA / "tiny.yaml"), cfg).mounting_separability()
    rotation = table[table["kind"] == "rotation"]
    assert list(rotation["axis"]) == ["roll", "pitch", "yaw"] and not rotation["separable"].any()
    assert rotation["ratio_mounting_free"].to_numpy() == pytest.approx(1.0, abs=1e-3)
    assert table.loc[table["kind"] == "non-orthogonality", "separable"].all()


def test_cli_plan_on_the_default_campaign_prints_and_writes_the_tables(tmp_path, capsys):
    assert cli.main(["plan", str(ROOT / "config" / "scenarios" / "mom.yaml"), "--out", str(tmp_path),
                     "--config", str(CONFIG)]) == 0
    printed = capsys.readouterr().out
    assert "pairs the plan cannot separate" in printed and "sf_nonlinearity" in printed
    assert "if the reference's mounting is estimated from these data" in printed
    table = pd.read_csv(tmp_path / "plan.csv")
    combos = table["parameter"].isin(["sf_mean", "sf_asym"])
    assert (~combos).sum() == 24 and combos.sum() == 12 and set(table["unit"]) == {"ppm", "arcsec"}
    assert table.loc[combos, "resolved"].all()
    assert table["predicted_sd"].between(1.0, 50.0).all()   # tens of ppm and a few arcsec on MOM
    detection = pd.read_csv(tmp_path / "plan_detection.csv")
    assert set(detection["effect"]) == {"bias_drift", "sf_nonlinearity", "g_sensitivity", "gravity_offset",
                                        "st_latency", "st_correlated_noise", "st_jitter"}
    for needs_accelerometer in ("g_sensitivity", "gravity_offset"):
        row = detection.set_index("effect").loc[needs_accelerometer]
        assert not row["detectable"] and "needs 'acc_" in row["why_not"]
    assert (tmp_path / "plan.png").stat().st_size > 0


def test_cli_plan_compares_two_plans_side_by_side(tmp_path, capsys):
    assert cli.main(["plan", str(DATA / "tiny.yaml"), str(DATA / "onerate_nonlinearity.yaml"), "--out", str(tmp_path),
                     "--config", str(CONFIG)]) == 0
    printed = capsys.readouterr().out
    assert "A = tiny, B = onerate_nonlinearity" in printed
    assert set(pd.read_csv(tmp_path / "plan.csv")["plan"]) == {"tiny", "onerate_nonlinearity"}


def test_cli_plan_refuses_a_maneuver_it_cannot_fly_naming_the_file_and_field(tmp_path, capsys):
    scenario = yaml.safe_load((DATA / "tiny.yaml").read_text())
    scenario["maneuvers"][2]["direction"] = "both"
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(scenario))
    assert cli.main(["plan", str(path), "--out", str(tmp_path), "--config", str(CONFIG)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: maneuvers[2].direction" in err


def test_cli_plan_writes_under_results_plan_by_default_not_the_current_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["plan", str(DATA / "tiny.yaml"), "--config", str(CONFIG)]) == 0
    assert "wrote results/plan/plan.csv" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "results" / "plan").iterdir()) == [
        "plan.csv", "plan.png", "plan_detection.csv"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results"]


def test_a_plan_with_the_gauss_markov_clock_on_the_angle_turned_is_the_wls_sd_on_that_clock(cfg):
    """The scenario's clock (100 s a radian) goes to the plan's maneuvers as a campaign.yaml that states it
    gives them: the bound is the correlated model's WLS sd on that clock within 2 %, and not the time
    clock's; the printout names the clock."""
    scenario = gauss_markov_tiny()
    scenario["star_tracker"]["gm_clock_s_per_rad"] = 100.0
    predicted = plan.plan(scenario, cfg)
    assert "over 30 s on a clock of time and 100 s a radian turned;" in plan.report([predicted])
    stated = plan.stated_noise(scenario, cfg["noise"])
    campaign, truth = simulate.simulate(scenario)
    maneuvers = [dataclasses.replace(preprocess.slice_maneuver(campaign, m.id), gm_clock_s_per_rad=100.0)
                 for m in campaign.maneuvers]
    names = ["scale_factor", "misalignment", "bias", "st_correlated_noise"]
    spec = ModelSpec.build("correlated", effects.resolve("correlated", names, {}), campaign.channels)
    theta0 = spec.core_vector(truth_vector(campaign.channels, truth))
    total = {**stated, "sigma_cross_arcsec": np.sqrt(50.0), "sigma_about_arcsec": np.sqrt(800.0),
             "st_gm_fraction": 0.5, "st_gm_tau_s": 30.0}
    est = wls(maneuvers, spec, total, covariance.log_sigma_of(total, correlated=True), theta0, correlation_time_s=30.0)
    np.testing.assert_allclose(predicted.crlb_sd, np.sqrt(np.diag(est.cov)), rtol=0.02)
    on_time = plan.plan(gauss_markov_tiny(), cfg).crlb_sd
    assert np.max(np.abs(predicted.crlb_sd / on_time - 1)) > 0.05

