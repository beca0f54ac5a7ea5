"""Telemetry as it comes: each corruption gets a message a user can act on; messy but valid
campaigns pass, with what was found counted; nothing unidentified drags what is identified."""

import json
import types

import numpy as np
import pandas as pd
import pytest

from gyrocal import checks
from gyrocal.checks import outliers, physics, sampling, saturation, sensing
from gyrocal.inference.sampling.refusals import EstimateError
from gyrocal.io.calibration import parameter_rows
from gyrocal.io.telemetry import read_campaign
from gyrocal.maneuvers import preprocess
from gyrocal.model.units import rad_to_arcsec
from gyrocal.pipeline import cli
from gyrocal.pipeline.settings import PosteriorSettings
from gyrocal.pipeline.steps import posterior as posterior_step

import mutations
from conftest import rerun_from, run_campaign

EXPECTED = {
    "gyro increments in degrees": "57.",
    "gyro increments 1000x too large": "1000 times too large",
    "gyro rates instead of increments": "rates in rad/s rather than increments",
    "gyro cumulative angle": "cumulative angle",
    "gyro gap inside a rotation": "inside maneuver yaw_pos",
    "scalar-first quaternions under q1..q4": "scalar first",
    "5 s star-tracker clock offset": "shifted by -5 s",
    "overlapping maneuvers": "overlap",
    "axis label names the wrong axis": "axis label wrong",
    "direction label is the wrong one": "opposite of the label's direction",
    "window with no rotation": "a hold, or a motion too small to calibrate on",
    "valid=2": "column 'valid': must be 0 or 1, got 2",
    "boresight given as strings": "star_tracker.boresight_body: must be a non-zero 3-vector",
    "gyro: a scalar": "gyro: must be a mapping",
    "unquoted direction: -": 'quote a direction, direction: "-"',
    "blank line, then a NaN": "line 22, column 'dtg1_roll': value is NaN",
    "t_start: true": "t_start: must be a time in seconds, got True",
    "a dead channel through the roll maneuvers": "column 'dtg1_roll', lines 3402-6601: reads exactly 0",
    "a channel stuck at a constant": "reads the constant 3e-06 rad",
    "a frozen reference mid-turn": "the attitude repeats exactly for 20 samples",
    "a gyro cell that lost its exponent": "lost its exponent",
}


def validate_cli(directory, capsys):
    code = cli.main(["validate", str(directory)])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize("case", sorted(mutations.REFUSED))
def test_validate_refuses_each_corruption_with_a_message_naming_the_cause(case, tiny, tmp_path, capsys):
    directory = tmp_path / "campaign"
    mutations.corrupted_copy(tiny[0], directory, mutations.REFUSED[case])
    code, out, err = validate_cli(directory, capsys)
    assert code == 2, out
    assert EXPECTED[case] in err
    assert "Traceback" not in err and "np.int64" not in err


def test_every_refused_case_has_its_expected_message():
    assert set(EXPECTED) == set(mutations.REFUSED)


def test_quaternions_rounded_to_5_decimals_are_renormalised_and_counted(tiny, tmp_path, capsys):
    directory = tmp_path / "campaign"
    mutations.corrupted_copy(tiny[0], directory, mutations.quaternion_decimals(5))
    campaign, _ = checks.read_checked(directory)
    assert campaign.st_renormalised > 0.5 * (campaign.st_valid == 1).sum()
    assert np.allclose(np.linalg.norm(campaign.st_quat[campaign.st_valid == 1], axis=1), 1.0, atol=1e-12)


def test_a_hyphenated_directory_without_a_name_gets_a_safe_default_name(tiny, tmp_path, capsys):
    directory = tmp_path / "my-campaign"
    mutations.corrupted_copy(tiny[0], directory, mutations.hyphen_name)
    code, out, _ = validate_cli(directory, capsys)
    assert code == 0 and "campaign my_campaign: OK" in out


def test_a_window_without_holds_is_a_warning_and_classic_gives_no_number(tiny, tmp_path):
    from gyrocal.inference.fit import classic
    from gyrocal.maneuvers import preprocess
    directory = tmp_path / "campaign"
    mutations.corrupted_copy(tiny[0], directory, mutations.no_hold)
    campaign, findings = checks.read_checked(directory)
    assert any("yaw_pos: no inertial hold before or after" in w for w in findings.warnings)
    assert classic.classic(preprocess.slice_maneuver(campaign, "yaw_pos")).empty


def test_a_maneuver_without_holds_reports_the_error_between_its_first_and_last_reference_samples(tiny, tmp_path):
    """The report's before/after table once indexed an empty hold (the RepoIMU trials with the
    reference every 1 s reached it and crashed). Corrected with the truth, the error left by
    the rotation (scale errors of about 1000 ppm over 90 deg: hundreds of arcsec) shrinks to
    the noise."""
    from gyrocal.criticism import verdict as report

    from conftest import truth_vector
    directory = tmp_path / "campaign"
    mutations.corrupted_copy(tiny[0], directory, mutations.no_hold)
    campaign, _ = checks.read_checked(directory)
    data = preprocess.slice_maneuver(campaign, "yaw_pos")
    truth = truth_vector(data.channels, tiny[1])
    n = len(truth.channels)
    nominal = type(truth)(truth.channels, np.zeros(n), np.zeros(n), np.zeros((n, 3)), truth.bias_rad_s)
    table = report.correction_effect([data], [truth], [nominal])
    in_loop = table[table["in loop"]].iloc[0]
    assert in_loop["before norm"] > 100.0 and in_loop["after norm"] < 60.0


def test_a_clean_campaign_raises_no_warning_outlier_or_excursion(tiny):
    _, findings = checks.read_checked(tiny[0])
    assert findings.warnings == [] and findings.outliers == []


def test_neighbour_residual_is_zero_on_a_line_and_isolates_a_spike():
    x = np.column_stack([np.arange(20.0), -2.0 * np.arange(20.0)])
    assert np.allclose(sensing.neighbour_residual(x), 0.0)
    x[7] += [10.0, 0.0]
    r = sensing.neighbour_residual(x)
    assert r[7, 0] == pytest.approx(10.0)
    assert np.allclose(np.delete(r, 7, axis=0), 0.0)


def test_the_reference_noise_seen_by_the_checks_does_not_grow_when_the_reference_is_thinned(tiny, tmp_path):
    """The rotation checks' noise is the noise of one reference sample (tiny: 5 arcsec across the
    boresight, 20 about it), whatever the interval between samples; the reference's own
    interval rotations, which the checks once took for it, are the motion per interval."""
    thinned = tmp_path / "thinned"
    mutations.corrupted_copy(tiny[0], thinned, lambda d: (d / "star_tracker.csv").write_text(
        "".join(line for i, line in enumerate((d / "star_tracker.csv").read_text().splitlines(True)) if i % 5 < 1)))
    for directory, step in ((tiny[0], 1.0), (thinned, 5.0)):
        campaign = read_campaign(directory)
        for m in campaign.maneuvers:
            sensed = sensing.sense(preprocess.slice_maneuver(campaign, m.id))
            assert np.median(sensed.dt) == pytest.approx(step)
            assert 4.0 < rad_to_arcsec(sensing.reference_noise_rad(sensed)) < 30.0


def test_robust_covariance_recovers_the_bulk_despite_gross_outliers():
    rng = np.random.default_rng(5)
    cov = np.array([[4.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 9.0]])
    x = rng.multivariate_normal(np.zeros(3), cov, size=4000)
    x[:40] += 200.0
    assert np.allclose(outliers.robust_covariance(x), cov, rtol=0.1, atol=0.15)


def test_a_parameter_with_no_information_is_prior_only_and_one_with_little_is_not(tiny):
    from gyrocal.inference.fit.identification import uninformed
    from gyrocal.inference.fit.likelihood import Stats
    from gyrocal.io.telemetry import read_campaign
    from gyrocal.model.spec import baseline
    spec = baseline(read_campaign(tiny[0]).channels)
    info = 1.0 / spec.prior_sd_si**2
    A = np.diag(info * 50.0)
    A[3, 3] = 0.0
    A[5, 5] = 0.005 * info[5]
    A[7, 7] = 0.02 * info[7]
    flagged = uninformed(Stats(A, np.zeros(len(spec)), 0.0, 0.0, 10), spec)
    assert sorted(flagged) == sorted([spec.labels[3], spec.labels[5]])
    assert "constant" in flagged[spec.labels[3]]


@pytest.fixture(scope="module")
def outlier_run(tiny, tmp_path_factory, config):
    base = tmp_path_factory.mktemp("outliers")
    directory = base / "campaign"
    lines = mutations.corrupted_copy(tiny[0], directory, mutations.st_outliers)
    run_campaign(directory, base / "out", config)
    return base / "out", lines


@pytest.mark.full
def test_five_star_tracker_outliers_are_listed_and_left_out(outlier_run):
    out, lines = outlier_run
    info = json.loads((out / "input.json").read_text())
    assert sorted(o["line"] for o in info["star_tracker_outliers"]) == sorted(lines)
    assert info["rows"]["star_tracker_outliers"] == 5
    assert all(300 < o["size_arcsec"] < 850 for o in info["star_tracker_outliers"])
    html = (out / "report.html").read_text()
    assert "Star-tracker outliers left out of the fit (5)" in html


@pytest.mark.full
def test_five_outliers_move_no_estimate_by_more_than_half_an_sd(outlier_run, tiny_run):
    out, _ = outlier_run
    clean = pd.read_csv(tiny_run[0] / "baseline/calibration.csv")
    dirty = pd.read_csv(out / "baseline/calibration.csv")
    shift = np.abs(dirty["mean"] - clean["mean"]) / clean["sd"]
    assert shift.max() < 0.5


def test_a_reference_excursion_is_listed_as_one_and_left_out(tiny, tmp_path):
    directory = tmp_path / "campaign"
    lines = mutations.corrupted_copy(tiny[0], directory, mutations.st_excursion)
    campaign, findings = checks.read_checked(directory)
    away = [o for o in findings.outliers if o.kind == "excursion"]
    assert sorted(o.line for o in away) == lines and len(lines) == 2
    assert all(1500 < o.size_arcsec < 2500 for o in away)
    assert [o for o in findings.outliers if o.kind == "outlier"] == []
    assert findings.warnings == []
    m = campaign.maneuvers[0].id
    data = preprocess.slice_maneuver(campaign, m, [o.time_s for o in findings.outliers])
    assert data.counts["st_outliers"] == 2


def test_an_excursion_comes_back_inside_the_maneuver_within_its_time_and_jumps():
    t = np.arange(12.0)
    beyond = np.zeros(12, dtype=bool)
    beyond[[4, 5]] = True
    near = beyond.copy()
    near[[3, 6]] = True
    jumps = beyond.copy()
    assert list(np.flatnonzero(outliers.excursion_runs(near, beyond, jumps, t, 5.0))) == [3, 4, 5, 6]
    assert not outliers.excursion_runs(near, beyond, jumps, t, 2.5).any()
    assert not outliers.excursion_runs(near, beyond, np.zeros(12, dtype=bool), t, 5.0).any()
    assert not outliers.excursion_runs(near, np.zeros(12, dtype=bool), jumps, t, 5.0).any()
    near[[0, 1, 11]] = beyond[[0, 1, 11]] = jumps[[0, 1, 11]] = True
    assert list(np.flatnonzero(outliers.excursion_runs(near, beyond, jumps, t, 5.0))) == [3, 4, 5, 6]
    near[[0, 1, 11]] = beyond[[0, 1, 11]] = jumps[[0, 1, 11]] = False
    near[7:10] = True                 # edges that stretch it past the limit: the core's time decides
    assert list(np.flatnonzero(outliers.excursion_runs(near, beyond, jumps, t, 4.0))) == [3, 4, 5, 6, 7, 8, 9]
    near[7:11] = True                 # past twice the limit: only the core goes
    assert list(np.flatnonzero(outliers.excursion_runs(near, beyond, jumps, t, 4.0))) == [4, 5]


@pytest.fixture(scope="module")
def unflown_run(tiny, tmp_path_factory, config):
    base = tmp_path_factory.mktemp("unflown")
    directory = base / "campaign"
    mutations.corrupted_copy(tiny[0], directory, mutations.drop_maneuver("pitch_neg"))
    run_campaign(directory, base / "out", config)
    return base / "out"


def test_a_direction_never_flown_is_prior_only_and_its_posterior_is_the_prior(unflown_run):
    cal = pd.read_csv(unflown_run / "baseline/calibration.csv")
    flagged = cal[cal["prior_only"]]
    assert sorted(flagged["channel"] + "." + flagged["parameter"]) == ["dtg1_pitch.sf_neg", "dtg2_pitch.sf_neg"]
    assert np.allclose(flagged["sd"], 5000.0, rtol=0.05)
    assert np.allclose(flagged["mean"], 0.0, atol=0.1 * 5000.0)


def test_a_prior_only_parameter_drags_no_identified_one(unflown_run, tiny_run, tiny):
    """Without pitch_neg, the parameters no pitch rotation informs (scale factors of the roll and
    yaw channels, misalignments toward roll and yaw) stay where the full campaign puts them; every
    informed parameter still covers the truth."""
    full = parameter_rows(pd.read_csv(tiny_run[0] / "baseline/calibration.csv"))
    cal = parameter_rows(pd.read_csv(unflown_run / "baseline/calibration.csv"))
    informed = ~cal["prior_only"].to_numpy()
    pitch_channel = cal["channel"].str.endswith("_pitch")
    untouched = informed & ~(pitch_channel & cal["parameter"].str.startswith("sf")) & (cal["parameter"] != "mis_pitch")
    shift = (np.abs(cal["mean"] - full["mean"]) / full["sd"])[untouched]
    assert untouched.sum() == 16 and shift.max() < 0.25
    truth = tiny[1]["parameters"]
    z = [(r.mean - truth[r.channel][r.parameter]) / r.sd for r in cal[informed].itertuples()]
    assert np.max(np.abs(z)) < 3.5


def test_the_verdict_names_the_missing_maneuver(unflown_run):
    html = (unflown_run / "report.html").read_text()
    assert "NO-GO" in html
    assert "dtg1_pitch.sf_neg (no -pitch turn in the data: turn about -pitch)" in html
    assert "No correction for dtg1_pitch, dtg2_pitch" in html


def test_a_point_estimate_beyond_the_bounds_stops_before_sampling_naming_parameter_and_maneuver(
        tiny_run, config, tmp_path):
    out, _ = tiny_run
    with pytest.raises(EstimateError) as err:
        paths, ids = rerun_from(out, tmp_path)
        settings = PosteriorSettings.of({**config, "priors": {**config["priors"], "sf_bound_ppm": 100.0}})
        posterior_step.run(paths.maneuvers(ids), paths.model("baseline").point_estimate,
                    paths.model("baseline"), settings)
    message = str(err.value)
    assert "dtg1_roll.sf_pos = 14" in message and "(bound 100," in message
    assert "fits maneuver" in message
    assert not (tmp_path / "baseline/posterior.nc").exists()


def test_every_json_output_is_strict_json(tiny_run):
    out, _ = tiny_run

    def refuse(constant):
        raise ValueError(f"non-standard JSON constant {constant}")

    files = sorted(out.rglob("*.json"))
    assert len(files) >= 4
    for path in files:
        json.loads(path.read_text(), parse_constant=refuse)


@pytest.mark.full
def test_same_config_and_seed_give_byte_identical_outputs(tiny, short_chains, tmp_path):
    """Byte for byte, and the posterior's netCDF (whose bytes hold a creation time) by its content
    and attributes."""
    import shutil

    import arviz as az
    names = ("baseline/calibration.csv", "baseline/diagnostics.json", "report.html", "input.json")
    run_campaign(tiny[0], tmp_path / "out", short_chains)
    first = {name: (tmp_path / "out" / name).read_bytes() for name in names}
    shutil.copy(tmp_path / "out/baseline/posterior.nc", tmp_path / "first.nc")
    run_campaign(tiny[0], tmp_path / "out", short_chains)
    for name in names:
        assert (tmp_path / "out" / name).read_bytes() == first[name], name
    a, b = az.from_netcdf(tmp_path / "first.nc"), az.from_netcdf(tmp_path / "out/baseline/posterior.nc")
    for group in a.groups():
        assert a[group].attrs == b[group].attrs
        assert a[group].equals(b[group])


def test_a_noise_no_sensor_can_have_stops_before_sampling_with_the_residuals(tiny_run):
    import dataclasses

    from gyrocal.inference.fit.estimate import PointEstimate
    from gyrocal.inference.sampling.refusals import check_noise
    from gyrocal.maneuvers import preprocess
    out, npz = tiny_run
    est = PointEstimate.load(out / "baseline/point_estimate.npz")
    collapsed = dataclasses.replace(est, log_sigma=est.log_sigma + np.array([-8.0, 0.0, 0.0]))
    check_noise([preprocess.ManeuverData.load(p) for p in npz], est)
    with pytest.raises(EstimateError, match=r"sigma_cross_arcsec .* \(stated 5\).*RMS about roll, pitch, yaw"):
        check_noise([preprocess.ManeuverData.load(p) for p in npz], collapsed)


def sensed_turn(clip_rad_s=None, seed=0):
    """A 200 s turn about roll at 0.5 rad/s (gyro at 10 Hz, reference at 1 Hz with 1e-4 rad
    noise), the gyro's roll rate clipped at ``clip_rad_s``; pitch and yaw only a slow limit cycle,
    whose peaks the gyro holds for many samples, far below the reference's noise."""
    rng = np.random.default_rng(seed)
    gyro_time = np.arange(0, 200.05, 0.1)
    true = np.zeros((len(gyro_time) - 1, 3))
    true[:, 0] = 0.5 * 0.1
    true[:, 1:] = 5e-6 * 0.1 * np.sin(2 * np.pi * gyro_time[1:, None] / [90.0, 130.0] + rng.uniform(0, 6, 2))
    body = true.copy()
    if clip_rad_s is not None:
        body[:, 0] = np.minimum(body[:, 0], clip_rad_s * 0.1)
    st_time = gyro_time[::10]
    data = types.SimpleNamespace(id="roll_pos", dt=np.diff(gyro_time), gyro_time=gyro_time, st_time=st_time,
                                 st_interval=lambda: (np.clip(np.searchsorted(gyro_time, st_time) - 1, 0, None), None))
    d_gyro = body.reshape(-1, 10, 3).sum(axis=1)
    d_st = true.reshape(-1, 10, 3).sum(axis=1) + rng.normal(0, 1e-4, (len(st_time) - 1, 3))
    return sensing.Sensed(data, body, d_gyro, d_st, np.diff(st_time))


@pytest.mark.parametrize("seed", range(5))
def test_saturation_is_not_called_on_an_axis_that_only_sees_noise(seed):
    findings = checks.Findings()
    assert not saturation.reference_evidence(sensed_turn(seed=seed), 0.02, findings)
    assert findings.errors == []


def test_a_gyro_clipped_below_the_turn_rate_is_refused_with_its_count():
    findings = checks.Findings()
    assert saturation.reference_evidence(sensed_turn(clip_rad_s=0.4), 0.02, findings)
    assert "2000 gyro samples about roll" in findings.errors[0] and "1.250 times as fast" in findings.errors[0]


@pytest.mark.parametrize("every", [10, 40])
def test_a_reference_too_sparse_for_the_turn_is_named_with_the_interval_it_needs(every):
    """At 0.5 rad/s (28.6 deg/s) a reference every 1 s sees 29 deg turns, checked as usual; every 4 s
    it sees 115 deg, where its own rotation could be wrapped by whole turns: named, asking for a
    sample at least every 90 / 28.6 = 3.1 s. A gyro turning 115 deg within each of its own
    0.1 s samples (a unit slip) is not blamed on the reference."""
    gyro_time = np.arange(0, 200.05, 0.1)
    body = np.tile([0.05, 0.0, 0.0], (len(gyro_time) - 1, 1))
    st_time = gyro_time[::every]
    data = types.SimpleNamespace(id="roll_pos", dt=np.diff(gyro_time), st_time=st_time)
    d_gyro = body.reshape(-1, every, 3).sum(axis=1)
    why = physics.undersampled(sensing.Sensed(data, body, d_gyro, d_gyro, np.diff(st_time)))
    if every == 10:
        assert why == ""
    else:
        assert "turns 115 deg between the reference samples at 0 s and 4 s (50 intervals" in why
        assert "peak rate, 29 deg/s, keep the reference at least every 3.1 s" in why
    slip = body * 40
    assert physics.undersampled(sensing.Sensed(data, slip, slip.reshape(-1, every, 3).sum(axis=1),
                                                       d_gyro, np.diff(st_time))) == ""


def test_a_maneuver_shorter_than_two_blocks_takes_halved_blocks_and_one_too_short_for_any_is_refused_naming_it():
    """Each LOO block is predicted from the rest of its maneuver, which must keep 10 samples: a maneuver
    of one 60-s block (or one whose rest holds 9) takes 30-s blocks; one of 12 samples leaves fewer than
    10 outside its largest block down to blocks of two samples, and is refused with its span (it used to
    crash in a Cholesky factorisation)."""
    from gyrocal.inference.sampling.predictive import maneuver_block_s, sample_blocks
    from gyrocal.inference.sampling.refusals import check_blocks
    enough = types.SimpleNamespace(id="yaw_pos", st_time=np.arange(0.0, 70.0))
    one_block = types.SimpleNamespace(id="roll_neg", st_time=np.arange(0.0, 59.0))
    nearly = types.SimpleNamespace(id="pitch_pos", st_time=np.arange(0.0, 69.0))
    tiny = types.SimpleNamespace(id="yaw_neg", st_time=np.arange(0.0, 12.0))
    assert [maneuver_block_s(m.st_time, 60.0) for m in (enough, one_block, nearly, tiny)] == [60.0, 30.0, 30.0, None]
    assert np.bincount(sample_blocks(one_block.st_time, 60.0)).tolist() == [30, 29]
    check_blocks([enough, one_block, nearly], 60.0)
    with pytest.raises(EstimateError, match=r"yaw_neg spans 11 s \(12 samples\).*Lengthen the maneuver"):
        check_blocks([enough, tiny], 60.0)


@pytest.mark.parametrize("shift_s", [0.3, -0.7])
def test_the_clock_offset_is_found_to_a_fraction_of_a_sample(tiny, tmp_path, shift_s):
    from gyrocal.io.telemetry import read_campaign
    mutations.corrupted_copy(tiny[0], tmp_path / "c", mutations.st_clock_offset(shift_s))
    campaign = read_campaign(tmp_path / "c")
    for m in ("yaw_pos", "roll_neg"):
        found = sampling.clock_offset_s(sensing.sense(preprocess.slice_maneuver(campaign, m)))
        assert found == pytest.approx(-shift_s, abs=0.02)  # the star tracker late: the gyro's clock early
