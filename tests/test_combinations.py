"""The identifiable combinations (sf_mean, sf_asym), their resolution against the prior, the mounting's
inseparable misalignment combinations, and calibration.csv's derived rows through every reader."""

import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from gyrocal.criticism import agreement, verdict
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.sampling.priors import posterior_spec
from gyrocal.io import calibration
from gyrocal.model import channels as ch
from gyrocal.model import combinations
from gyrocal.model.spec import ModelSpec, baseline
from gyrocal.pipeline import cli
from gyrocal.report import fleet, resolution, review

from conftest import run_campaign

TRIAD = [ch.Channel("gyro_x", None, "roll"), ch.Channel("gyro_y", None, "pitch"), ch.Channel("gyro_z", None, "yaw")]


def symmetric_spec() -> ModelSpec:
    """The triad with one symmetric ``sf`` per channel (as a symmetric scale-factor model declares it)."""
    params = []
    for p in baseline(TRIAD).parameters:
        if p.name == "sf_pos":
            params.append(replace(p, label=f"{p.owner}.sf", name="sf"))
        elif p.name != "sf_neg":
            params.append(p)
    return ModelSpec("symmetric", TRIAD, params, ["scale_factor", "misalignment", "bias"])


def test_the_combinations_sd_is_sqrt_a_c_a_of_the_scale_factors_covariance():
    """sd 3000 and 2500 ppm correlated -0.93: sf_mean's sd is sqrt(a' C a) with a = (1/2, 1/2), far
    below either's, sf_asym's with a = (1, -1) above both; the draws give the same to sampling error."""
    spec = baseline(TRIAD)
    combos = combinations.scale_combinations(spec)
    assert [c.label for c in combos] == [f"{g}.{n}" for g in ("gyro_x", "gyro_y", "gyro_z") for n in ("sf_mean", "sf_asym")]
    pos, neg = spec.index("gyro_x.sf_pos"), spec.index("gyro_x.sf_neg")
    cov = np.diag(np.full(len(spec), 1.0))
    c2 = np.array([[3000.0**2, -0.93 * 3000 * 2500], [-0.93 * 3000 * 2500, 2500.0**2]])
    cov[np.ix_([pos, neg], [pos, neg])] = c2
    sd, prior, ratio = combinations.prior_relative(cov, combinations.weights(combos[:2]), [p.prior_sd for p in spec.parameters])
    mean_sd = np.sqrt(np.array([0.5, 0.5]) @ c2 @ np.array([0.5, 0.5]))
    asym_sd = np.sqrt(np.array([1.0, -1.0]) @ c2 @ np.array([1.0, -1.0]))
    assert sd == pytest.approx([mean_sd, asym_sd], rel=1e-12)
    assert mean_sd == pytest.approx(np.sqrt((3000**2 + 2500**2 - 2 * 0.93 * 3000 * 2500) / 4), rel=1e-12)
    assert mean_sd < 600 and asym_sd > 5000
    assert prior == pytest.approx([np.sqrt(2) * 5000 / 2, np.sqrt(2) * 5000], rel=1e-12)
    assert ratio[0] <= combinations.RESOLVED_RATIO_MAX < ratio[1]
    draws = np.random.default_rng(1).multivariate_normal(np.zeros(len(spec)), cov, size=200_000)
    sampled = combinations.combination_draws(draws, combos[:2]).std(axis=0, ddof=1)
    assert sampled == pytest.approx([mean_sd, asym_sd], rel=0.01)


def test_a_symmetric_scale_factor_is_the_mean_and_has_no_asymmetry_row():
    spec = symmetric_spec()
    combos = combinations.scale_combinations(spec)
    assert [c.label for c in combos] == ["gyro_x.sf_mean", "gyro_y.sf_mean", "gyro_z.sf_mean"]
    assert combos[0].weights[spec.index("gyro_x.sf")] == 1.0 and combos[0].weights.sum() == 1.0
    assert combinations.combination_values({"sf": 120.0, "mis_yaw": 3.0}) == {"sf_mean": 120.0}
    assert combinations.combination_values({"sf_pos": 100.0, "sf_neg": 40.0}) == {"sf_mean": 70.0, "sf_asym": 60.0}


def test_a_combination_of_a_prior_only_part_is_prior_only_only_when_every_part_is():
    spec = baseline(TRIAD).with_prior_only({"gyro_x.sf_neg": "no -roll maneuver"})
    combos = {c.label: c for c in combinations.scale_combinations(spec)}
    assert not combos["gyro_x.sf_mean"].prior_only
    spec = spec.with_prior_only({"gyro_x.sf_pos": "no +roll maneuver"})
    assert combinations.scale_combinations(spec)[0].prior_only


def test_the_combinations_cramer_rao_bound_is_infinite_on_an_uninformed_direction():
    """Information only on sf_pos + sf_neg (a +rotation and a -rotation that read alike): the
    mean's bound is finite and sqrt(a' A^+ a); the asymmetry's is infinite."""
    spec = baseline(TRIAD)
    A = np.eye(len(spec)) * 1e12
    pos, neg = spec.index("gyro_x.sf_pos"), spec.index("gyro_x.sf_neg")
    u = np.zeros(len(spec))
    u[[pos, neg]] = 1e6   # per unit of sf (SI): 1 ppm is 1e-6
    A[np.ix_([pos, neg], [pos, neg])] = 0.0
    A += np.outer(u, u) * 4.0
    bound = combinations.crlb_sd(A, spec, combinations.scale_combinations(spec)[:2])
    # the data see 1e6 (sf_pos + sf_neg) (SI) with precision 4: the sum's sd is 0.5 ppm, the mean's 0.25
    assert bound[0] == pytest.approx(0.25, rel=1e-6)
    assert np.isinf(bound[1])


def test_advice_names_the_motion_that_would_resolve_each_combination():
    assert combinations.advice("sf_asym", "roll", set()) == "turn about +roll and -roll, as far each way"
    assert combinations.advice("sf_mean", "roll", {("roll", "+")}) == "turn about -roll (the data turn only +roll)"
    both = {("roll", "+"), ("roll", "-")}
    assert "with rest before, between and after" in combinations.advice("sf_asym", "roll", both)
    assert combinations.advice("mis_yaw", "roll", both) == "turn about yaw, either way (the data hold no such turn)"
    assert combinations.advice("mis_yaw", "roll", both | {("yaw", "-")}) == "turn more, or larger, about yaw"
    sentence = combinations.channel_sentence(TRIAD[0], [
        {"parameter": "sf_mean", "sd": 700.0, "ratio": 0.2, "unit": "ppm"},
        {"parameter": "sf_asym", "sd": 6000.0, "ratio": 0.85, "unit": "ppm"}], both)
    assert sentence.startswith("gyro_x: resolved sf_mean (sd 700 ppm); sf_asym (sf_pos - sf_neg) is not (sd 6000 ppm, "
                               "0.85 of its prior's): turn about +roll and -roll with rest")
    wide = combinations.channel_sentence(TRIAD[0], [
        {"parameter": "sf_mean", "sd": 400.0, "ratio": 0.03, "unit": "ppm", "width": 1600.0, "limit": 2000.0},
        {"parameter": "mis_yaw", "sd": 220.0, "ratio": 0.06, "unit": "arcsec", "width": 880.0, "limit": 300.0}], both)
    assert wide == ("gyro_x: resolved sf_mean (sd 400 ppm); mis_yaw is informed (0.06 of its prior's sd) but its 95 % "
                    "interval is 880 arcsec wide, over the 300 arcsec limit: turn about yaw, either way (the data hold no such "
                    "turn).")


def test_the_mounting_takes_up_the_triads_rotation_and_leaves_its_non_orthogonality():
    """Every misalignment well known as fitted: with the mounting free, the triad's rotation about
    each axis is back at its prior (ratio 1), each pair's non-orthogonality is as well known as fitted."""
    spec = baseline(TRIAD)
    cov = np.diag([(p.prior_sd * 0.01) ** 2 for p in spec.parameters])
    rows = pd.DataFrame(combinations.mounting_separability(cov, spec)).set_index(["axis", "kind"])
    assert len(rows) == 6
    assert rows.loc[("yaw", "rotation"), "combination"] == "(gyro_x.mis_pitch - gyro_y.mis_roll) / 2"
    assert rows["ratio_fitted"].to_numpy() == pytest.approx(0.01, rel=1e-6)
    rotation = rows.xs("rotation", level="kind")
    assert rotation["ratio_mounting_free"].to_numpy() == pytest.approx(1.0, abs=1e-3)
    square = rows.xs("non-orthogonality", level="kind")
    assert square["ratio_mounting_free"].to_numpy() == pytest.approx(0.01, rel=1e-3)


def test_prior_directions_name_the_direction_left_to_the_prior():
    spec = baseline(TRIAD)
    prior = np.array([p.prior_sd for p in spec.parameters])
    scaled = np.eye(len(spec)) * 0.01**2
    pos, neg = spec.index("gyro_y.sf_pos"), spec.index("gyro_y.sf_neg")
    v = np.zeros(len(spec))
    v[[pos, neg]] = [1 / np.sqrt(2), -1 / np.sqrt(2)]
    scaled += np.outer(v, v) * (0.9**2 - 0.01**2)
    table = resolution.prior_directions(spec, scaled * np.outer(prior, prior))
    assert len(table) == 1 and table["sd_over_prior"].iloc[0] == pytest.approx(0.9, abs=1e-3)
    assert table["direction"].iloc[0] == "+0.71 gyro_y.sf_pos -0.71 gyro_y.sf_neg"


@pytest.fixture(scope="module")
def short_run(tiny, short_chains, tmp_path_factory):
    out = tmp_path_factory.mktemp("combinations")
    cfg = dict(short_chains, models={"baseline": ["scale_factor", "misalignment", "bias"]})
    npz = run_campaign(tiny[0], out, cfg, truth_path=tiny[0].parent / "truth.json")
    return out, npz, cfg


def test_on_a_simulated_campaign_sf_mean_is_narrower_than_each_direction_and_covers_the_truth(tiny, short_run):
    table = pd.read_csv(short_run[0] / "baseline/calibration.csv").set_index(["channel", "parameter"])
    for name, values in tiny[1]["parameters"].items():
        width = table["ci95_high"] - table["ci95_low"]
        assert width[name, "sf_mean"] < min(width[name, "sf_pos"], width[name, "sf_neg"])
        truth = combinations.combination_values(values)["sf_mean"]
        assert table.loc[(name, "sf_mean"), "ci95_low"] <= truth <= table.loc[(name, "sf_mean"), "ci95_high"]
        point = table.loc[[(name, "sf_pos"), (name, "sf_neg")], "point"].mean()
        assert table.loc[(name, "sf_mean"), "point"] == pytest.approx(point, rel=1e-12)


def test_calibration_csv_with_derived_rows_goes_through_every_reader(tiny, short_run, tmp_path, capsys):
    """The correction, prior_from, compare-campaigns (same frame and turned), the fleet, the verdict's
    checks and the report's tables read a calibration.csv with sf_mean and sf_asym rows."""
    out, _, cfg = short_run
    path = out / "baseline/calibration.csv"
    table = pd.read_csv(path)
    est = PointEstimate.load(out / "baseline/point_estimate.npz")
    spec = est.spec
    assert calibration.combination_rows(table).sum() == 12
    assert len(calibration.parameter_rows(table)) == len(spec)
    assert len(calibration.core_rows(spec, table)) == spec.n_core
    params = calibration.posterior_mean_params(spec, table)
    assert spec.core_vector(params) == pytest.approx(spec.to_si(table["mean"].to_numpy()[:spec.n_core]), rel=1e-12)
    prior = posterior_spec(spec, cfg["priors"], path)
    assert [p.prior_sd for p in prior.parameters] == pytest.approx(table["sd"].to_numpy()[:len(spec)], rel=1e-12)
    assert all(not p.label.endswith(("sf_mean", "sf_asym")) for p in prior.parameters)
    assert cli.main(["compare-campaigns", str(path), str(path)]) == 0
    printed = capsys.readouterr().out
    assert "VERDICT: AGREE: 0 of 24 parameters" in printed and "combinations (not counted above): 0 of 12" in printed
    turn = Rotation.from_rotvec(np.deg2rad([0.2, -0.1, 0.3]))
    turned = agreement.into_frame(table, turn).set_index(["channel", "parameter"])
    for name in {c.name for c in spec.channels}:
        pos, neg = turned.loc[(name, "sf_pos"), "mean"], turned.loc[(name, "sf_neg"), "mean"]
        assert turned.loc[(name, "sf_mean"), "mean"] == pytest.approx((pos + neg) / 2, abs=1e-6)
        assert turned.loc[(name, "sf_asym"), "mean"] == pytest.approx(pos - neg, abs=1e-6)
    summary = fleet.summary([{"campaign": "tiny", "model": "baseline", "verdict": "GO"}],
                            {("tiny", "baseline"): table})
    assert set(summary["parameter"]) >= {"sf_mean", "sf_asym"} and len(summary) == len(table)
    sampler = json.loads((out / "baseline/sampler.json").read_text())
    assert verdict.convergence_check(table, spec, sampler, cfg["convergence"]).figure is not None
    tables = review.paper_tables(table, spec.channels, ["dtg3_roll", "dtg1_pitch", "dtg2_yaw"], tiny[1]["parameters"])
    assert "truth 1200" in tables["table2"].set_index("channel").loc["dtg1_roll", review.COMBINATION_HEADINGS["sf_mean"]]
    resolved = resolution.resolution_table(prior, table)
    assert len(resolved) == len(table)


def test_the_review_says_per_channel_what_is_resolved(short_run):
    html = (short_run[0] / "report.html").read_text()
    assert "id='resolution-sentences'" in html and 'id="resolution"' in html
    assert "dtg1_roll: resolved sf_mean (sd" in html
