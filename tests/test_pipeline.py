"""Each workflow step in isolation on a tiny campaign, and the statistics on the default one."""

import copy
import dataclasses
import json
import shutil

import numpy as np
import pandas as pd
import pytest

from gyrocal.inference import errormodel
from gyrocal.inference.fit import estimate
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.fit.likelihood import campaign_stats
from gyrocal.inference.noise import covariance
from gyrocal.inference.sampling.priors import model_priors
from gyrocal.io import calibration, telemetry
from gyrocal.model import channels as ch
from gyrocal.model import combinations, correction, effects
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import PPM
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import PosteriorSettings
from gyrocal.pipeline.steps import common
from gyrocal.pipeline.steps import posterior as posterior_step

from conftest import rerun_from, truth_vector


@pytest.fixture(scope="module")
def mom_estimate(mom, tmp_path_factory, config):
    """The default campaign validated, preprocessed (no figures), its classic table and its baseline
    point estimate: what the tests of the WLS, the classic method and the linearisation read. The
    posterior and the review of the same campaign are test_report's (`mom_run`)."""
    from gyrocal.pipeline import run
    out = tmp_path_factory.mktemp("mom_estimate")
    paths = CampaignPaths.under(out)
    cfg = copy.deepcopy(config)
    cfg["models"] = {"baseline": ["scale_factor", "misalignment", "bias"]}
    ids = run.calibrate_campaign(mom[0], paths, cfg, ["baseline"], figures=False, through="point_estimate")
    return out, paths.maneuvers(ids)


def calibration_with_truth(out, truth):
    table = pd.read_csv(out / "baseline/calibration.csv")
    t = {name: {**values, **combinations.combination_values(values)} for name, values in truth["parameters"].items()}
    table["truth"] = [t[r.channel][r.parameter] for r in table.itertuples()]
    return table


def posterior_again(out, npz, cfg, tmp_path):
    """The posterior step once more on a finished run's point estimate, with ``cfg``, under ``tmp_path``."""
    paths, ids = rerun_from(out, tmp_path)
    posterior_step.run(paths.maneuvers(ids), paths.model("baseline").point_estimate,
                    paths.model("baseline"), PosteriorSettings.of(cfg))


def test_validate_step_records_rows_and_checksums(tiny_run):
    info = json.loads((tiny_run[0] / "input.json").read_text())
    assert info["campaign"] == "tiny" and len(info["maneuvers"]) == 6
    assert set(info["checksums_sha256"]) == {"campaign.yaml", "star_tracker.csv", "gyro.csv"}
    assert info["rows"]["star_tracker_invalid"] > 0


def test_preprocess_step_writes_table_figure_and_counts(tiny_run):
    out = tiny_run[0]
    table = pd.read_csv(out / "preprocess/yaw_pos.csv")
    assert {"time", "rate_yaw_deg_s", "set0_error_yaw_arcsec", "set1_error_roll_arcsec"} <= set(table.columns)
    assert table["rate_yaw_deg_s"].max() == pytest.approx(0.5, rel=0.02)
    assert (out / "preprocess/yaw_pos.png").read_bytes()[:4] == b"\x89PNG"
    z = np.load(out / "preprocess/yaw_pos.npz")
    counts = dict(zip(z["count_names"], z["count_values"]))
    # read = used + flagged invalid + the sample at t_start itself, which seeds the attitude
    assert counts["st_read"] - counts["st_used"] - counts["st_invalid"] in (0, 1)
    assert counts["st_used"] > 250


def test_preprocess_step_writes_every_maneuver_whole_or_leaves_the_directory_as_it_was(tiny, tiny_run, tmp_path,
                                                                                       monkeypatch):
    from gyrocal.maneuvers import preprocess
    from gyrocal.pipeline.steps import preprocess as preprocess_step
    out = tmp_path / "preprocess"
    paths = CampaignPaths.under(tmp_path)
    shutil.copy(tiny_run[0] / "input.json", paths.input_json)
    ids = [m.id for m in telemetry.read_meta(tiny[0])["maneuvers"]]
    assert preprocess_step.run(tiny[0], paths.input_json, paths.preprocess, figures=False) == ids
    assert sorted(p.name for p in out.iterdir()) == sorted([f"{i}.{e}" for i in ids for e in ("npz", "csv")]
                                                           + ["reference_interval.json"])
    for i in ids:
        assert (out / f"{i}.csv").read_bytes() == (tiny_run[0] / f"preprocess/{i}.csv").read_bytes()

    made = []

    def third_fails(data):
        made.append(data.id)
        if len(made) == 3:
            raise RuntimeError("disk full")
        return table_of(data)

    table_of = preprocess.error_table
    monkeypatch.setattr(preprocess, "error_table", third_fails)
    for earlier in out.iterdir():  # an earlier run's files, told apart from what this run would write
        earlier.write_bytes(b"earlier run")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(RuntimeError, match="disk full"):
        preprocess_step.run(tiny[0], paths.input_json, paths.preprocess, figures=False)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["input.json", "preprocess"]


def test_calibration_csv_follows_the_contract(tiny_run):
    table = pd.read_csv(tiny_run[0] / "baseline/calibration.csv")
    assert list(table.columns) == ["channel", "parameter", "unit", "point", "mean", "sd", "ci95_low",
                                   "ci95_high", "r_hat", "ess_bulk", "prior_only"]
    assert len(table) == 24 + 12 and table["channel"].nunique() == 6
    assert table["parameter"].iloc[24:].tolist() == ["sf_mean", "sf_asym"] * 6   # derived rows after the parameters
    assert set(table["unit"]) == {"ppm", "arcsec"}
    assert (table["ci95_low"] < table["mean"]).all() and (table["mean"] < table["ci95_high"]).all()


def test_tiny_posterior_converges_and_covers_a_truth_that_is_not_the_papers(tiny, tiny_run):
    sampler = json.loads((tiny_run[0] / "baseline/sampler.json").read_text())
    assert sampler["converged"], sampler["failed_parameters"]
    assert sampler["steps"] >= 50 * sampler["tau_max_steps"]
    table = calibration_with_truth(tiny_run[0], tiny[1])
    assert (table["r_hat"] < 1.01).all() and (table["ess_bulk"] >= 400).all()
    inside = (table["ci95_low"] <= table["truth"]) & (table["truth"] <= table["ci95_high"])
    derived = calibration.combination_rows(table)
    assert inside[~derived].sum() >= 21, table[~inside]
    assert inside[derived].sum() >= 10, table[~inside]


def test_same_seed_same_numbers(tiny_run, config, tmp_path):
    out, npz = tiny_run
    posterior_again(out, npz, config, tmp_path)
    assert (tmp_path / "baseline/posterior_summary.csv").read_text() == (out / "baseline/posterior_summary.csv").read_text()


def test_a_run_that_cannot_converge_says_so(tiny_run, config, tmp_path, caplog):
    out, npz = tiny_run
    cfg = copy.deepcopy(config)
    # chains that end at max_steps before another chunk fits (50 + 10 > 59) are kept, not converged;
    # one that could go on but never converge in budget stops at once (tests/test_sampler_budget.py)
    cfg["sampler"].update(initial_steps=50, chunk_steps=10, max_steps=59, min_tau_multiple=1000)
    posterior_again(out, npz, cfg, tmp_path)
    info = json.loads((tmp_path / "baseline/sampler.json").read_text())
    assert info["converged"] is False and info["chain_length_ok"] is False
    assert "DID NOT CONVERGE" in caplog.text


def test_correction_file_inverts_the_channel_model(tiny, tiny_run):
    doc = json.loads((tiny_run[0] / "baseline/correction.json").read_text())
    assert "omega_body" in doc["convention"]
    in_loop = [s for s in doc["sets"] if s["in_loop"]]
    assert [s["channels"] for s in in_loop] == [["dtg3_roll", "dtg1_pitch", "dtg2_yaw"]]
    channels = telemetry.read_meta(tiny[0])["channels"]
    truth = truth_vector(channels, tiny[1])
    truth.bias_rad_s[:] = 0
    rng = np.random.default_rng(0)
    raw = rng.normal(0, 0.01, (200, 3))
    w = np.sign(raw) * (0.002 + np.abs(raw))
    for entry in doc["sets"]:
        exact = correction.correction_for_set(truth, entry["channels"])
        idx = [truth.channels.index(next(c for c in truth.channels if c.name == n)) for n in entry["channels"]]
        outputs = ch.measure(w, truth)[:, idx]
        assert np.allclose(correction.apply(exact, outputs), w, atol=1e-15)
        # the estimated correction leaves a residual of the order of the posterior sd
        assert np.abs(correction.apply(entry, outputs) - w).max() < 5e-4 * np.abs(w).max()


def test_sequential_campaign_takes_priors_from_an_earlier_posterior(tiny_run, config, tmp_path):
    """Parameters the earlier calibration.csv holds take its mean and sd as their prior; the
    others keep their effect's declared prior; a parameter in another unit is refused."""
    out, _ = tiny_run
    est = PointEstimate.load(out / "baseline/point_estimate.npz")
    first = pd.read_csv(out / "baseline/calibration.csv")
    earlier = first[first["channel"] != "dtg3_roll"]
    earlier.to_csv(tmp_path / "earlier.csv", index=False)
    priors = model_priors(est, config["priors"], tmp_path / "earlier.csv")
    spec = est.spec
    assert set(earlier["parameter"]) >= {"sf_mean", "sf_asym"}   # derived rows are in the file, and ignored
    for r in calibration.parameter_rows(earlier).itertuples():
        i = spec.index(f"{r.channel}.{r.parameter}")
        assert priors.mean[i] == pytest.approx(r.mean * spec.si_per_unit[i], rel=1e-12)
        assert priors.sd[i] == pytest.approx(r.sd * spec.si_per_unit[i], rel=1e-12)
    own = [spec.index(f"dtg3_roll.{n}") for n in ("sf_pos", "sf_neg", "mis_pitch", "mis_yaw")]
    assert np.all(priors.mean[own] == 0.0)
    assert priors.sd[own] == pytest.approx([5000 * PPM, 5000 * PPM, 1000 / 206264.806, 1000 / 206264.806])
    earlier.assign(unit="deg").to_csv(tmp_path / "wrong_unit.csv", index=False)
    with pytest.raises(ValueError, match=r"dtg1_roll\.sf_pos is in deg, but this model declares it in ppm"):
        model_priors(est, config["priors"], tmp_path / "wrong_unit.csv")


def test_wls_is_within_3_sd_of_the_truth_on_the_default_scenario(mom, mom_estimate):
    out, _ = mom_estimate
    est = PointEstimate.load(out / "baseline/point_estimate.npz")
    truth = est.spec.core_vector(truth_vector(est.spec.channels, mom[1]))
    z = (est.theta - truth) / np.sqrt(np.diag(est.cov))
    assert np.all(np.abs(z) < 3), z


@pytest.mark.full
def test_posterior_95_intervals_cover_the_papers_values(mom, mom_run):
    """At least 22 of the 24 channel parameters inside their central 95 % interval, and 10 of the 12
    combinations (sf_mean, sf_asym)."""
    out, _ = mom_run
    table = calibration_with_truth(out, mom[1])
    inside = (table["ci95_low"] <= table["truth"]) & (table["truth"] <= table["ci95_high"])
    derived = calibration.combination_rows(table)
    assert inside[~derived].sum() >= 22 and inside[derived].sum() >= 10, table[~inside]
    assert json.loads((out / "baseline/sampler.json").read_text())["converged"]


def test_classic_reproduces_the_papers_values_within_its_own_sd(mom, mom_estimate):
    """Each value's bias from its maneuver's 400 s holds, its sd from the stated noise (the walk,
    the star tracker and the hold bias's own error): every value within 4 sd of the truth."""
    out, _ = mom_estimate
    classic = pd.read_csv(out / "classic.csv", keep_default_na=False)
    truth = mom[1]["parameters"]
    assert len(classic) == 24 and (classic["bias_source"] == "holds").all()
    sf = classic["unit"] == "ppm"
    assert 20 < classic["sd"][sf].median() < 60 and 2 < classic["sd"][~sf].median() < 10  # measured: 31, 4.6
    for row in classic.itertuples():
        assert abs(row.value - truth[row.channel][row.parameter]) < 4 * row.sd, row


def test_linearised_model_agrees_with_the_exact_one_to_1_percent_of_the_sd(mom, mom_estimate):
    """Posterior draws pushed 3 sd out: the exact model's departure from the linear one
    moves the estimate by under 1 % of each posterior sd."""
    out, npz = mom_estimate
    maneuvers = common.load_maneuvers(npz)
    est = PointEstimate.load(out / "baseline/point_estimate.npz", effects.LIBRARY)
    lins, noises = estimate.linearize_all(maneuvers, est)
    var = covariance.variances(est.log_sigma)
    stats = campaign_stats(noises, var)
    cov = np.linalg.inv(stats.A)
    sd = np.sqrt(np.diag(cov))
    rng = np.random.default_rng(5)
    for _ in range(2):
        shift = 3 * rng.standard_normal(len(sd)) * sd
        deltas = []
        for m, (data, lin) in enumerate(zip(maneuvers, lins)):
            exact = errormodel.linearize(data, est.spec, est.theta + shift, est.biases[m]).z
            linear = lin.z - np.einsum("msip,p->msi", lin.design, shift)
            deltas.append(covariance.build(dataclasses.replace(lin, z=exact - linear), est.boresight))
        moved = cov @ campaign_stats(deltas, var).b
        assert np.all(np.abs(moved) < 0.01 * sd), np.max(np.abs(moved) / sd)


def test_psis_table_gives_arvizs_elpd_loo_its_se_and_p_loo(tiny_run):
    import arviz as az

    from gyrocal.criticism import comparison
    from gyrocal.inference.sampling import inferencedata
    idata = az.from_netcdf(tiny_run[0] / "baseline/posterior.nc")
    blocks = pd.read_csv(tiny_run[0] / "baseline/elpd_blocks.csv")
    expected = az.loo(idata, pointwise=True)
    totals = comparison.loo_totals(blocks)
    assert totals == {"elpd_loo": float(expected.elpd_loo), "elpd_loo_se": float(expected.se),
                      "p_loo": float(expected.p_loo)}
    np.testing.assert_allclose(blocks["pareto_k"], expected.pareto_k.values, rtol=0, atol=0)
    assert list(blocks["block"]) == [str(b) for b in idata.log_likelihood["block"].values]
    again = inferencedata.loo_blocks(idata, "baseline")
    for column in ("elpd_loo", "p_loo", "pareto_k"):
        np.testing.assert_array_equal(again[column].to_numpy(), blocks[column].to_numpy())


def test_saved_linearisation_is_the_models_to_the_bit_and_older_files_still_load(tiny_run, tmp_path):
    out, npz = tiny_run
    maneuvers = common.load_maneuvers(npz)
    est = PointEstimate.load(out / "baseline/point_estimate.npz")
    assert len(est.at_estimate) == len(maneuvers)
    for m, data in enumerate(maneuvers):
        saved = est.linearize(maneuvers, m)
        assert saved is est.at_estimate[m]
        fresh = errormodel.linearize(data, est.spec, est.theta, est.biases[m])
        assert saved.maneuver == fresh.maneuver and saved.sets == fresh.sets
        for field in dataclasses.fields(fresh):
            assert np.array_equal(getattr(saved, field.name), getattr(fresh, field.name)), field.name
    # a file written before the linearisation was saved: the same estimate, linearised when asked
    with np.load(out / "baseline/point_estimate.npz") as z:
        older = {k: z[k] for k in z.files if not k.startswith("lin") and k != "n_linearized"}
    np.savez(tmp_path / "older.npz", **older)
    old = PointEstimate.load(tmp_path / "older.npz")
    assert old.at_estimate == () and np.array_equal(old.theta, est.theta)
    assert np.array_equal(old.linearize(maneuvers, 0).design, est.at_estimate[0].design)
    # a step that never linearises leaves them on disk
    bare = PointEstimate.load(out / "baseline/point_estimate.npz", linearizations=False)
    assert bare.at_estimate == () and np.array_equal(bare.theta, est.theta) and bare.spec.labels == est.spec.labels
    # a linearisation of another maneuver, or about other parameters, is not taken for this one's
    assert est.linearize(maneuvers[1:], 0).maneuver == maneuvers[1].id
    moved = dataclasses.replace(est, theta=est.theta + 1e-6)
    assert moved.linearize(maneuvers, 0) is not est.at_estimate[0]
    assert not np.array_equal(moved.linearize(maneuvers, 0).z, est.at_estimate[0].z)


def test_a_trial_steps_residual_is_the_linearisations_z_to_the_bit(tiny_run):
    """The WLS evaluates a trial step by `errormodel.residuals`, without the Jacobian: the same ``z``
    as `errormodel.linearize`, with and without extra effects, at parameters away from the estimate."""
    out, npz = tiny_run
    maneuvers = common.load_maneuvers(npz)
    est = PointEstimate.load(out / "baseline/point_estimate.npz", linearizations=False)
    fx = effects.resolve("latency", ["scale_factor", "misalignment", "bias", "st_latency"], {})
    for spec in (est.spec, ModelSpec.build("latency", fx, maneuvers[0].channels)):
        theta = np.random.default_rng(2).normal(0.0, 1e-4, len(spec))
        for m, data in enumerate(maneuvers):
            z = errormodel.residuals(data, spec, theta, est.biases[m] + 1e-6)
            assert z.tobytes() == errormodel.linearize(data, spec, theta, est.biases[m] + 1e-6).z.tobytes()


def test_wls_given_its_start_linearisation_finds_the_same_estimate_to_the_bit(tiny_run):
    out, npz = tiny_run
    maneuvers = common.load_maneuvers(npz)
    est = PointEstimate.load(out / "baseline/point_estimate.npz")
    start = dataclasses.replace(est, at_estimate=())
    lins = [start.linearize(maneuvers, m) for m in range(len(maneuvers))]
    args = (maneuvers, est.spec, est.stated_noise, est.log_sigma, est.theta * 0.9, est.biases, est.chi0)
    given = estimate.wls(*args, lins0=[errormodel.linearize(d, est.spec, est.theta * 0.9, est.biases[m])
                                       for m, d in enumerate(maneuvers)])
    computed = estimate.wls(*args)
    assert lins and given.nfev == computed.nfev
    for name in ("theta", "cov", "biases", "chi0"):
        assert np.array_equal(getattr(given, name), getattr(computed, name), equal_nan=True), name


def test_a_finished_step_exits_zero_at_once_with_its_log_written(tmp_path):
    import subprocess
    import sys
    log = tmp_path / "step.log"
    code = ("import logging\nfrom gyrocal.pipeline.steps import common\n"
            f"common.start({str(log)!r})\nlogging.getLogger('gyrocal').info('written whole')\n"
            "print('before', flush=False)\ncommon.finish()\nprint('after')\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    assert run.stdout == "before\n"
    assert "written whole" in log.read_text()
