"""Tabular telemetry through a mapping, and two calibrations compared: on small files whose truth
is known."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy.spatial.transform import Rotation

from gyrocal.criticism import agreement
from gyrocal.errors import InputError
from gyrocal.io import importer, rests, telemetry
from gyrocal.pipeline import cli


def repoimu_like(path, rate_rad_s=0.5, n=400, dt=0.01, t0=3.0, dropouts=(50, 51), quat_format="{:.10g}", scale=None):
    """A RepoIMU-format file: a turn about x at a rate that varies, Vicon scalar first, gyro rates in
    rad/s, accelerometer and magnetometer columns; all-zero quaternions at ``dropouts``; the
    quaternions printed with ``quat_format``, those of the rows in ``scale`` (row: factor) scaled."""
    t = t0 + dt * np.arange(n)
    rate = rate_rad_s * np.sin(2 * np.pi * (t - t0) / (n * dt))
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * dt)])
    quat = Rotation.from_rotvec(np.outer(angle, [1.0, 0.0, 0.0])).as_quat()
    wxyz = quat[:, [3, 0, 1, 2]]
    wxyz[list(dropouts)] = 0.0
    for row, factor in (scale or {}).items():
        wxyz[row] *= factor
    rows = np.column_stack([t, wxyz, np.full((n, 3), 9.81), rate, np.zeros(n), np.zeros(n), np.ones((n, 3))])
    header = "Time (s);Vicon Orientation;;;;IMU Acceleration;;;IMU Gyroscope;;;IMU Magnetometer;;;\n"
    header += ";W;X;Y;Z;X;Y;Z;X;Y;Z;X;Y;Z;\n"
    path.write_text(header + "\n".join(";".join(quat_format.format(v) if 1 <= i <= 4 else f"{v:.10g}"
                                                 for i, v in enumerate(r)) + ";" for r in rows) + "\n")
    return t, quat, rate


def test_import_writes_a_campaign_per_the_contract(tmp_path):
    t, quat, rate = repoimu_like(tmp_path / "Trial_A.csv")
    repoimu_like(tmp_path / "Trial_B.csv", t0=10.0, dropouts=())
    out = tmp_path / "campaign"
    _, counts = importer.import_files("repoimu", out, [tmp_path / "Trial_A.csv", tmp_path / "Trial_B.csv"])
    again = telemetry.read_campaign(out)
    assert [m.id for m in again.maneuvers] == ["Trial_A", "Trial_B"]
    assert [m.direction for m in again.maneuvers] == ["both", "both"]
    assert [m.noise_group for m in again.maneuvers] == ["Trial_A", "Trial_B"]  # one noise level per recording
    assert again.maneuvers[0].axis == "roll"
    assert again.channel_names == ["gyro_x", "gyro_y", "gyro_z"]
    assert all(c.dtg is None for c in again.channels)
    assert sorted(again.extras()) == ["acc_x", "acc_y", "acc_z", "mag_x", "mag_y", "mag_z"]
    assert counts["Trial_A"]["reference_dropouts"] == 2 and counts["Trial_B"]["reference_dropouts"] == 0
    assert list(np.flatnonzero(again.st_valid == 0)) == [50, 51]
    first = slice(0, len(t))
    valid = again.st_valid[first] == 1
    assert np.allclose(again.st_quat[first][valid], quat[valid], atol=1e-9)
    step = np.diff(t)
    assert np.allclose(again.gyro_columns["gyro_x"][first][1:], 0.5 * (rate[1:] + rate[:-1]) * step)
    second = again.maneuvers[1]
    assert second.t_start == pytest.approx(again.maneuvers[0].t_end + 0.01)


def test_a_reference_interval_keeps_every_nth_reference_row_and_counts_the_rest(tmp_path):
    t, quat, _ = repoimu_like(tmp_path / "Trial_A.csv")
    out = tmp_path / "campaign"
    campaign, counts = importer.import_files("repoimu", out, [tmp_path / "Trial_A.csv"], reference_interval_s=0.3)
    again = telemetry.read_campaign(out)
    kept = list(range(0, 400, 30)) + [399]
    assert np.allclose(again.st_time, t[kept] - t[0])
    assert len(again.gyro_time) == 400
    assert counts["Trial_A"]["reference_kept"] == 15
    assert counts["Trial_A"]["reference_dropouts"] == 0  # rows 50 and 51, the dropouts, are not kept
    valid = again.st_valid == 1
    assert np.allclose(again.st_quat[valid], quat[kept][valid], atol=1e-9)
    assert "reference kept every 0.3 s: 15 samples, 385 left out between them" in importer.report(campaign, counts, out)
    sparse = r"Trial_A\.csv.*no stretch of it has 10 valid reference samples kept \(8 in all, of 9 kept"
    with pytest.raises(InputError, match=sparse):
        importer.import_files("repoimu", tmp_path / "sparse", [tmp_path / "Trial_A.csv"], reference_interval_s=0.5)


def test_the_printed_precision_is_read_off_each_column_as_decimals_or_significant_digits():
    """RepoIMU prints 5 significant digits (a "1" among them stands for 1.0000); a fixed format
    prints as many decimals in every value. The unit in the last place follows."""
    text = ["1", "0.98275", "-0.030836", "2.4976e-006", "-0"]
    unit, words = importer.printed_quantum(text, [float(v) for v in text])
    assert words == "5 significant digits" and unit.tolist() == pytest.approx([1e-4, 1e-5, 1e-6, 1e-10, 1e-10])
    text = ["1.0000", "0.9876", "-0.0308", "0.0000"]
    unit, words = importer.printed_quantum(text, [float(v) for v in text])
    assert words == "4 decimals" and unit.tolist() == pytest.approx([1e-4] * 4)


def test_quaternions_rounded_to_two_decimals_are_written_unit_and_counted(tmp_path, capsys):
    """Rounded to 2 decimals, a quaternion's norm is off 1 by up to 5.8e-3 here (0.58 times the most
    that rounding can do): each is renormalised, the report says how many and why, and the campaign
    reader (validate's first step), which refuses a norm off 1 by more than 1e-3, finds nothing to
    renormalise."""
    repoimu_like(tmp_path / "Trial_A.csv", rate_rad_s=3.0, quat_format="{:.2f}")
    out = tmp_path / "campaign"
    assert cli.main(["import", "repoimu", str(out), str(tmp_path / "Trial_A.csv")]) == 0
    report = capsys.readouterr().out
    assert ("reference quaternions printed to 2 decimals: 374 renormalised (norm off 1 by up to 0.0058, at most "
            "0.58 times what rounding to those digits can do), none off by more than 2 times") in report
    again = telemetry.read_campaign(out)
    assert again.st_renormalised == 0 and list(np.flatnonzero(again.st_valid == 0)) == [50, 51]
    assert np.abs(np.linalg.norm(again.st_quat[again.st_valid == 1], axis=1) - 1).max() < 1e-12


def test_a_quaternion_off_unit_beyond_its_printed_digits_is_refused_with_its_line(tmp_path):
    """One quaternion scaled by 0.997 (off by 3.3 times what rounding to 3 decimals can do): not
    rounding, so it is flagged invalid, not renormalised, and named with its line and columns."""
    repoimu_like(tmp_path / "Trial_A.csv", rate_rad_s=3.0, quat_format="{:.3f}", scale={100: 0.997})
    campaign, counts = importer.build_campaign([tmp_path / "Trial_A.csv"], importer.read_mapping("repoimu"), "c")
    c = counts["Trial_A"]
    assert (c["reference_refused"], c["reference_renormalised"], c["reference_dropouts"]) == (1, 388, 2)
    assert c["reference_refused_first"]["line"] == 103 and c["reference_refused_first"]["times_rounding"] > 2
    assert list(np.flatnonzero(campaign.st_valid == 0)) == [50, 51, 100]
    assert ("1 off by more than 2 times refused and flagged invalid (not rounding: the source's own values, e.g. "
            "interpolated across a gap); the first at line 103, columns 2, 3, 4, 5: norm 0.99") in importer.report(
                campaign, counts, "c")


def test_reference_columns_that_hold_no_quaternion_are_refused_with_the_first_line(tmp_path):
    """Pointed at the accelerometer (norms near 17), most rows are off unit: the file is refused whole."""
    repoimu_like(tmp_path / "Trial_A.csv")
    mapping = importer.read_mapping("repoimu")
    mapping["reference"]["columns"] = [6, 7, 8, 9]
    with pytest.raises(telemetry.TelemetryError, match=r"Trial_A.csv: line 3, columns 6, 7, 8, 9 \(reference "
                       r"quaternion\): the reference quaternion's norm is 16.99.*as are 400 of the file's 400 quaternions. "
                       r"Check the mapping's reference.columns"):
        importer.build_campaign([tmp_path / "Trial_A.csv"], mapping, "c")


def test_a_declared_gyro_range_counts_the_samples_at_it(tmp_path):
    """``gyro.range`` in the mapping's gyro unit (rad/s, then deg/s): the rates that reach within 1 %
    of it are counted per channel in the report."""
    repoimu_like(tmp_path / "Trial_A.csv", rate_rad_s=0.5)
    mapping = importer.read_mapping("repoimu")
    mapping["gyro"] = {**mapping["gyro"], "unit": "rad/s", "range": 0.49}
    assert importer.declared_range_rad_s(mapping) == 0.49
    campaign, counts = importer.build_campaign([tmp_path / "Trial_A.csv"], mapping, "c")
    at = counts["Trial_A"]["at_range"]
    assert at == {"gyro_x": 62, "gyro_y": 0, "gyro_z": 0}
    assert ("gyro samples within 1% of the declared range 28.07 deg/s: gyro_x 62 (the gyro clips there"
            in importer.report(campaign, counts, "c"))
    mapping["gyro"] = {**mapping["gyro"], "unit": "deg/s", "range": 360}
    assert importer.declared_range_rad_s(mapping) == pytest.approx(2 * np.pi)
    mapping["gyro"]["range"] = -1
    with pytest.raises(telemetry.TelemetryError, match=r"gyro\.range must be a positive number"):
        importer.declared_range_rad_s(mapping)


def test_a_negative_reference_interval_is_refused(tmp_path):
    mapping = importer.read_mapping("repoimu")
    mapping["reference"]["sample_interval_s"] = -1
    (tmp_path / "mine.yaml").write_text(yaml.safe_dump(mapping))
    with pytest.raises(telemetry.TelemetryError, match="sample_interval_s must be a number of seconds >= 0"):
        importer.read_mapping(tmp_path / "mine.yaml")


def test_a_users_own_format_needs_a_mapping_not_code(tmp_path):
    t = 0.1 * np.arange(50)
    quat = Rotation.from_rotvec(np.outer(0.02 * np.arange(50), [0, 0, 1.0])).as_quat()
    increments_deg = np.zeros((50, 3))
    increments_deg[1:, 2] = np.rad2deg(0.02)
    frame = pd.DataFrame({"t": t, **{f"q{i}": quat[:, i] for i in range(4)},
                          "gx": increments_deg[:, 0], "gy": increments_deg[:, 1], "gz": increments_deg[:, 2]})
    frame.to_csv(tmp_path / "yaw_turn.csv", index=False)
    mapping = {"format": {"delimiter": ",", "header_rows": 1}, "time": {"column": 1},
               "reference": {"columns": [2, 3, 4, 5], "order": "xyzw"},
               "gyro": {"quantity": "increment", "unit": "deg", "columns": {"g_x": 6, "g_y": 7, "g_z": 8},
                        "axes": {"g_x": "roll", "g_y": "pitch", "g_z": "yaw"}},
               "maneuver": {"direction": "+"}}
    (tmp_path / "mine.yaml").write_text(yaml.safe_dump(mapping))
    importer.import_files(tmp_path / "mine.yaml", tmp_path / "out", [tmp_path / "yaw_turn.csv"])
    again = telemetry.read_campaign(tmp_path / "out")
    assert again.maneuvers[0].axis == "yaw" and again.maneuvers[0].direction == "+"
    assert np.allclose(again.gyro_columns["g_z"][1:], 0.02)


def test_a_mapping_that_points_past_the_columns_is_refused_naming_the_file(tmp_path, capsys):
    (tmp_path / "short.csv").write_text("a;b\nc;d\n1;2\n")
    code = cli.main(["import", "repoimu", str(tmp_path / "out"), str(tmp_path / "short.csv")])
    err = capsys.readouterr().err
    assert code == 2 and "short.csv" in err and "column" in err


def test_an_unknown_mapping_names_the_shipped_ones(capsys):
    code = cli.main(["import", "nosuch", "/tmp/never", "x.csv"])
    assert code == 2 and "repoimu" in capsys.readouterr().err


def broad_like(n=2500, rate_hz=100.0, missing=(10, 11, 700), motions=((500, 1000), (1500, 2000)), seed=1):
    """BROAD's arrays (``imu_gyr`` rad/s, ``opt_quat`` scalar first with NaN rows at ``missing``,
    ``imu_acc``, ``sampling_rate``): the gyro at rest (a bias and 0.002 rad/s of white noise) but in
    the rows ``motions``, where it turns about x at 1 rad/s."""
    rng = np.random.default_rng(seed)
    rate = np.array([0.001, -0.002, 0.008]) + 0.002 * rng.standard_normal((n, 3))
    for a, b in motions:
        rate[a:b, 0] += 1.0
    angle = np.cumsum(rate[:, 0]) / rate_hz
    quat = Rotation.from_rotvec(np.outer(angle, [1.0, 0.0, 0.0])).as_quat()[:, [3, 0, 1, 2]]
    quat[list(missing)] = np.nan
    return {"imu_gyr": rate, "opt_quat": quat, "imu_acc": np.tile([0.0, 0.0, 9.81], (n, 1)),
            "sampling_rate": np.array([[rate_hz]]), "info": "a synthetic trial"}


def test_a_mat_file_with_nan_reference_rows_imports_them_invalid_and_counted_as_free_motion(tmp_path):
    """BROAD's layout through the shipped ``broad`` mapping: the time counted at the file's
    sampling_rate, the NaN rows written valid = 0 (not refused) and counted, the MEMS class and the
    rate in campaign.yaml, and maneuvers with neither axis nor direction (free motion)."""
    from scipy.io import savemat

    savemat(tmp_path / "trial_A.mat", broad_like())
    out = tmp_path / "campaign"
    campaign, counts = importer.import_files("broad", out, [tmp_path / "trial_A.mat"], reference_interval_s=0)
    assert counts["trial_A"]["reference_missing"] == 3 and counts["trial_A"]["reference_dropouts"] == 0
    written = pd.read_csv(out / "star_tracker.csv")
    assert list(np.flatnonzero(written["valid"] == 0)) == [10, 11, 700] and len(written) == 2500
    assert written["time"].iloc[-1] == pytest.approx(24.99)
    meta = yaml.safe_load((out / "campaign.yaml").read_text())
    assert meta["gyro"] == {"sensor_class": "mems", "rate_hz": 100.0}
    assert all("axis" not in m and "direction" not in m for m in meta["maneuvers"])
    assert [m["noise_group"] for m in meta["maneuvers"]] == ["trial_A", "trial_A"]
    assert "3 reference rows missing (NaN or empty: no attitude, flagged invalid)" in importer.report(
        campaign, counts, out)


def test_a_file_is_cut_in_the_middle_of_each_inner_rest_seen_by_the_gyro(tmp_path):
    """Rest, motion (rows 500-999), rest, motion (1500-1999), rest at 100 Hz: averaged over 10
    samples the rate leaves rest 5 rows before a motion and returns 5 rows after it, so the rests
    are rows 0-495, 1005-1495 and 2005-2499; the file is cut in the middle of the inner one, at row
    1250, and the rests at its ends stay in its two maneuvers."""
    from scipy.io import savemat

    savemat(tmp_path / "trial_A.mat", broad_like())
    campaign, counts = importer.build_campaign([tmp_path / "trial_A.mat"], importer.read_mapping("broad"), "c")
    c = counts["trial_A"]
    assert c["rests_s"] == pytest.approx([(0.0, 4.95), (10.05, 14.95), (20.05, 24.99)])
    assert [(m.id, m.t_start, m.t_end) for m in campaign.maneuvers] == [("trial_A_1", 0.0, pytest.approx(12.49)),
                                                                        ("trial_A_2", pytest.approx(12.5), 24.99)]
    assert np.rad2deg(c["rest_sigma_rad_s"]) == pytest.approx(np.rad2deg(0.002), rel=0.15)


def test_a_free_maneuver_kept_whole_is_one_per_file(tmp_path):
    from scipy.io import savemat

    savemat(tmp_path / "trial_A.mat", broad_like())
    mapping = importer.read_mapping("broad")
    mapping["maneuver"] = {"free": True}
    campaign, _ = importer.build_campaign([tmp_path / "trial_A.mat"], mapping, "c")
    assert [(m.id, m.axis, m.direction, m.t_end) for m in campaign.maneuvers] == [("trial_A", None, None, 24.99)]


def test_windows_cut_each_span_into_equal_pieces_of_about_the_given_length():
    """``round(length / window)`` pieces per span, at least one, end to end: 25 s at 0.01 s in 10-s
    windows is 2 pieces (12.5 s each), 3 s is kept whole, and no window length keeps the spans."""
    assert rests.windows([(0, 2500)], 0.01, 10.0) == [(0, 1250), (1250, 2500)]
    assert rests.windows([(0, 300), (300, 2500)], 0.01, 10.0) == [(0, 300), (300, 1400), (1400, 2500)]
    assert rests.windows([(0, 2500)], 0.01, None) == [(0, 2500)]


def test_a_mapping_window_cuts_a_free_maneuver_into_windows_each_its_own_maneuver(tmp_path):
    """``maneuver.window_s: 5`` on a 25-s trial cut at its inner rest (two 12.5-s stretches): each
    stretch becomes two windows, free motion, one noise group, end to end without a shared row."""
    from scipy.io import savemat

    savemat(tmp_path / "trial_A.mat", broad_like())
    mapping = importer.read_mapping("broad")
    mapping["maneuver"] = {"split": "rests", "free": True, "window_s": 5.0}
    campaign, _ = importer.build_campaign([tmp_path / "trial_A.mat"], mapping, "c")
    got = [(m.id, m.axis, m.noise_group, round(m.t_start, 2), round(m.t_end, 2)) for m in campaign.maneuvers]
    assert got == [("trial_A_1", None, "trial_A", 0.0, 6.24), ("trial_A_2", None, "trial_A", 6.25, 12.49),
                   ("trial_A_3", None, "trial_A", 12.5, 18.74), ("trial_A_4", None, "trial_A", 18.75, 24.99)]


def test_an_hdf5_file_stored_columns_by_rows_reads_as_the_mat_file(tmp_path):
    """HDF5 as MATLAB v7.3 stores an N x 3 array (3 x N): turned, the same campaign as the .mat."""
    import h5py
    from scipy.io import savemat

    arrays = broad_like()
    savemat(tmp_path / "trial_A.mat", arrays)
    with h5py.File(tmp_path / "trial_A.h5", "w") as f:
        for name in ("imu_gyr", "opt_quat", "imu_acc", "sampling_rate"):
            f[name] = np.asarray(arrays[name]).T
    mapping = importer.read_mapping("broad")
    from_mat, _ = importer.build_campaign([tmp_path / "trial_A.mat"], mapping, "c", reference_interval_s=0)
    mapping["format"] = {"type": "hdf5"}
    from_h5, counts = importer.build_campaign([tmp_path / "trial_A.h5"], mapping, "c", reference_interval_s=0)
    assert counts["trial_A"]["reference_missing"] == 3
    assert np.array_equal(from_h5.gyro_columns["gyro_x"], from_mat.gyro_columns["gyro_x"])
    assert np.array_equal(from_h5.st_valid, from_mat.st_valid) and np.array_equal(from_h5.st_quat, from_mat.st_quat)


def test_a_nan_gyro_value_is_refused_naming_the_variable_row_and_column(tmp_path):
    from scipy.io import savemat

    arrays = broad_like()
    arrays["imu_gyr"][7, 1] = np.nan
    savemat(tmp_path / "trial_A.mat", arrays)
    with pytest.raises(InputError, match=r"trial_A.mat: variable imu_gyr, row 8, column 2 \(gyro gyro_y\): not a "
                                         r"number: nan \(1 such row\). Fix or drop those rows"):
        importer.build_campaign([tmp_path / "trial_A.mat"], importer.read_mapping("broad"), "c")


def test_a_variable_the_file_lacks_is_refused_naming_those_it_holds(tmp_path):
    from scipy.io import savemat

    arrays = broad_like()
    arrays["gyr"] = arrays.pop("imu_gyr")
    savemat(tmp_path / "trial_A.mat", arrays)
    with pytest.raises(InputError, match=r"the mapping's gyro is variable 'imu_gyr', which the file does not "
                                         r"hold. The file holds \['imu_acc', 'opt_quat', 'sampling_rate'\]"):
        importer.build_campaign([tmp_path / "trial_A.mat"], importer.read_mapping("broad"), "c")


def test_a_reference_with_fewer_rows_than_the_gyro_is_refused_naming_both_variables(tmp_path):
    from scipy.io import savemat

    arrays = broad_like()
    arrays["opt_quat"] = arrays["opt_quat"][::2]
    savemat(tmp_path / "trial_A.mat", arrays)
    with pytest.raises(InputError, match=r"variable opt_quat \(reference quaternion\): variable opt_quat has 1250 "
                                         r"rows, variable imu_gyr 2500: .* Resample one onto the other's times"):
        importer.build_campaign([tmp_path / "trial_A.mat"], importer.read_mapping("broad"), "c")


def test_empty_or_nan_reference_cells_in_a_csv_are_invalid_rows_and_other_text_is_refused(tmp_path):
    repoimu_like(tmp_path / "Trial_A.csv", dropouts=())
    lines = (tmp_path / "Trial_A.csv").read_text().splitlines()
    for row, cell in ((10, ""), (11, "NaN")):
        fields = lines[row + 2].split(";")
        fields[2] = cell
        lines[row + 2] = ";".join(fields)
    (tmp_path / "Trial_A.csv").write_text("\n".join(lines) + "\n")
    campaign, counts = importer.build_campaign([tmp_path / "Trial_A.csv"], importer.read_mapping("repoimu"), "c")
    assert counts["Trial_A"]["reference_missing"] == 2 and list(np.flatnonzero(campaign.st_valid == 0)) == [10, 11]
    assert counts["Trial_A"]["reference_precision"].startswith("10 significant digits")  # not "NaN"'s
    fields = lines[14].split(";")
    fields[2] = "oops"
    lines[14] = ";".join(fields)
    (tmp_path / "Trial_A.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"line 15, column 3 \(reference quaternion\): not a number: 'oops'"):
        importer.build_campaign([tmp_path / "Trial_A.csv"], importer.read_mapping("repoimu"), "c")


def test_the_mapping_sets_the_sensor_class_noise_and_rate_of_campaign_yaml(tmp_path):
    repoimu_like(tmp_path / "Trial_A.csv")
    mapping = importer.read_mapping("repoimu")
    mapping.update(sensor_class="fog", rate_hz=100.0, gyro_noise={"arw_deg_sqrt_h": 0.02},
                   star_tracker={"sigma_cross_arcsec": 5.0, "sigma_about_arcsec": 40.0})
    (tmp_path / "mine.yaml").write_text(yaml.safe_dump(mapping))
    importer.import_files(tmp_path / "mine.yaml", tmp_path / "out", [tmp_path / "Trial_A.csv"])
    again = telemetry.read_campaign(tmp_path / "out")
    assert again.gyro == {"arw_deg_sqrt_h": 0.02, "sensor_class": "fog", "rate_hz": 100.0}
    assert again.star_tracker["sigma_about_arcsec"] == 40.0 and again.maneuvers[0].axis == "roll"


@pytest.mark.parametrize("time, maneuver, match", [
    ({"column": 1, "rate_hz": 100.0}, None, r"the time is given 2 ways \(column, rate_hz\)"),
    ({"column": 1}, {"free": True, "direction": "+"}, "a free maneuver has no direction"),
])
def test_a_mapping_that_gives_the_time_twice_or_a_free_maneuver_a_direction_is_refused(tmp_path, time, maneuver,
                                                                                       match):
    mapping = importer.read_mapping("repoimu")
    mapping["time"] = time
    if maneuver:
        mapping["maneuver"] = maneuver
    (tmp_path / "mine.yaml").write_text(yaml.safe_dump(mapping))
    with pytest.raises(InputError, match=match):
        importer.read_mapping(tmp_path / "mine.yaml")


def test_a_time_that_does_not_increase_is_refused_with_its_line(tmp_path):
    t, _, _ = repoimu_like(tmp_path / "Trial_A.csv")
    lines = (tmp_path / "Trial_A.csv").read_text().splitlines()
    fields = lines[2 + 40].split(";")
    fields[0] = f"{t[39]:.10g}"
    lines[2 + 40] = ";".join(fields)
    (tmp_path / "Trial_A.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"Trial_A.csv: line 43, column 1 \(time\): the time 3.39 s does not increase "
                                         r"\(the row before holds 3.39 s\). Sort the rows"):
        importer.build_campaign([tmp_path / "Trial_A.csv"], importer.read_mapping("repoimu"), "c")


def test_gyrocal_import_of_a_mat_file_prints_its_missing_rows_rests_and_maneuvers(tmp_path, capsys):
    from scipy.io import savemat

    savemat(tmp_path / "trial_A.mat", broad_like())
    assert cli.main(["import", "--reference-interval", "0", "broad", str(tmp_path / "out"), str(tmp_path / "trial_A.mat")]) == 0
    out = capsys.readouterr().out
    assert "wrote " in out and "2 maneuvers" in out and "sensor class mems" in out
    assert "trial_A                  2500 rows at 100 Hz, 0 reference dropouts" in out
    assert "3 reference rows missing" in out and "0.00 to 4.95 s, 10.05 to 14.95 s, 20.05 to 24.99 s" in out
    assert "trial_A_1 (free motion, 0.00 to 12.49 s), trial_A_2 (free motion, 12.50 to 24.99 s)" in out
    assert "reference quaternions stored as binary floats: 0 renormalised" in out


BROAD = Path(__file__).resolve().parents[2] / "shared" / "data" / "broad"


@pytest.mark.skipif(not BROAD.is_dir(), reason=f"the BROAD trials are not at {BROAD} (see docs/usage.md, "
                                               "'gyrocal import')")
def test_the_broad_trials_import_the_gyro_at_its_full_rate_and_the_reference_every_tenth_second(tmp_path):
    """The two BROAD trials: the gyro at 285.714 Hz, the reference every 0.1 s (the mapping's: resampled
    from the cameras' frames, its error is white only rows apart), 162 and 306 NaN rows (markers
    occluded) of which 4 and 9 fall on kept rows, flagged invalid; one free maneuver and one noise group each
    (their rests open and close them; the gyro finds the motion where the data set's ``movement`` flag does);
    at --reference-interval 0 every row is kept and every NaN row counted."""
    files = [BROAD / "01_undisturbed_slow_rotation_A.mat", BROAD / "06_undisturbed_fast_rotation_A.mat"]
    campaign, counts = importer.import_files("broad", tmp_path / "broad", files)
    assert [c["reference_missing"] for c in counts.values()] == [4, 9]
    assert [c["rows"] for c in counts.values()] == [56940, 56380]
    assert [c["reference_kept"] for c in counts.values()] == [1965, 1946]
    _, every = importer.build_campaign(files[:1], importer.read_mapping("broad"), "c", reference_interval_s=0)
    assert every[files[0].stem]["reference_kept"] == 56940 and every[files[0].stem]["reference_missing"] == 162
    walk = campaign.gyro.pop("arw_deg_sqrt_h")  # measured in the trial's own rests (rests.arw_at_rest)
    assert campaign.gyro == {"sensor_class": "mems", "rate_hz": pytest.approx(285.714285714)}
    assert 0.3 < walk < 0.7  # deg/sqrt(h): a MEMS gyro's, not the DTG default 0.003
    still = campaign.star_tracker  # the reference's noise in the same rests (rests.reference_noise_at_rest)
    assert 30 < still["sigma_cross_arcsec"] < 70 and 15 < still["sigma_about_arcsec"] < 40  # OptiTrack at rest, 0.1 s
    assert still["boresight_body"] == [0.0, 0.0, 1.0] and still["sigma_is"] == "white"
    assert [(m.id, m.noise_group, m.axis) for m in campaign.maneuvers] == [(f.stem, f.stem, None) for f in files]
    first, last = counts["01_undisturbed_slow_rotation_A"]["rests_s"]
    assert first == pytest.approx((0.0, 33.5), abs=0.1) and last == pytest.approx((160.5, 199.29), abs=0.1)


def calibration(means, sds, prior_only=None):
    n = len(means)
    return pd.DataFrame({"channel": ["gyro_x"] * n, "parameter": [f"p{i}" for i in range(n)], "unit": ["ppm"] * n,
                         "mean": means, "sd": sds, "prior_only": prior_only or [False] * n})


def test_compare_campaigns_z_scores_use_both_sds():
    table = agreement.compare(calibration([100.0, 0.0], [3.0, 1.0]), calibration([108.0, 0.0], [4.0, 1.0]))
    assert table["z"].tolist() == pytest.approx([8.0 / 5.0, 0.0])


def test_compare_campaigns_verdict_and_exit_code(tmp_path, capsys):
    calibration([100.0, 0.0], [3.0, 1.0]).to_csv(tmp_path / "a.csv", index=False)
    calibration([100.0, 5.0], [3.0, 1.0], [False, True]).to_csv(tmp_path / "b.csv", index=False)
    calibration([120.0, 0.0], [3.0, 1.0]).to_csv(tmp_path / "c.csv", index=False)
    assert cli.main(["compare-campaigns", str(tmp_path / "a.csv"), str(tmp_path / "b.csv")]) == 0
    assert "VERDICT: AGREE" in capsys.readouterr().out
    assert cli.main(["compare-campaigns", str(tmp_path / "a.csv"), str(tmp_path / "c.csv")]) == 1
    out = capsys.readouterr().out
    assert "VERDICT: DISAGREE: 1 of 2" in out and "z = +4.71" in out


def test_compare_campaigns_lists_a_prior_only_parameter_as_such_not_with_a_nan_z(tmp_path, capsys):
    calibration([100.0, 0.0], [3.0, 1.0]).to_csv(tmp_path / "a.csv", index=False)
    calibration([100.0, 5.0], [3.0, 1.0], [False, True]).to_csv(tmp_path / "b.csv", index=False)
    cli.main(["compare-campaigns", str(tmp_path / "a.csv"), str(tmp_path / "b.csv")])
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if " p1 " in f" {line} ")
    assert row.split()[-2:] == ["prior-only", "True"] and "NaN" not in out and "nan" not in out


def triad_calibration(rows, sf):
    """A calibration table of a gyro triad from each channel's response row ``e_a + m`` (rad) and
    scale factor (dimensionless), in the units calibration.csv carries."""
    records = []
    for i, name in enumerate(["gyro_x", "gyro_y", "gyro_z"]):
        records += [{"channel": name, "parameter": p, "unit": "ppm", "mean": sf[i] / 1e-6, "sd": 100.0}
                    for p in ("sf_pos", "sf_neg")]
        records += [{"channel": name, "parameter": f"mis_{b}", "unit": "arcsec",
                     "mean": rows[i, j] / rows[i, i] * 206264.80624709636, "sd": 50.0}
                    for j, b in enumerate(("roll", "pitch", "yaw")) if j != i]
    return pd.DataFrame(records)


def test_a_calibration_turned_into_another_frame_is_the_same_gyro_seen_from_there():
    """The same gyros, their response rows expressed in a body frame turned by 0.4 deg: turning
    them back gives the first table's misalignments and scale factors to 1e-6 arcsec and ppm."""
    rows_a = np.eye(3) + np.deg2rad(np.array([[0, 0.2, -0.1], [0.05, 0, 0.3], [-0.15, 0.1, 0]]))
    sf_a = np.array([2e-3, -1e-3, 5e-4])
    turn = Rotation.from_rotvec(np.deg2rad([0.1, -0.2, 0.35]))
    turned = turn.inv().apply(rows_a * (1 + sf_a)[:, None])
    own = turned[np.arange(3), np.arange(3)]
    b = triad_calibration(turned / own[:, None], own - 1.0)
    back = agreement.into_frame(b, turn)
    a = triad_calibration(rows_a, sf_a)
    assert back["mean"].to_numpy() == pytest.approx(a["mean"].to_numpy(), abs=1e-6)
    assert back["sd"].tolist() == a["sd"].tolist()
    assert np.abs(b["mean"] - a["mean"])[b["parameter"].str.startswith("mis_")].max() > 300.0


def test_compare_campaigns_compares_misalignments_in_one_body_frame(tmp_path, capsys):
    """Two runs that aligned their references 0.3 deg apart about yaw see the same x gyro's
    misalignment toward pitch 1080 arcsec apart; turned into one frame they agree."""
    turn = Rotation.from_rotvec(np.deg2rad([0.0, 0.0, 0.3]))
    rows = np.eye(3) + np.deg2rad(np.array([[0, 0.1, 0.0], [0.0, 0, 0.0], [0.0, 0.0, 0]]))
    for run, mounting, frame_rows in (("a", Rotation.identity(), rows), ("b", turn.inv(), turn.inv().apply(rows))):
        (tmp_path / run / "baseline").mkdir(parents=True)
        (tmp_path / run / "input.json").write_text(json.dumps({"mounting": {"quat": mounting.as_quat().tolist()}}))
        own = frame_rows[np.arange(3), np.arange(3)]
        triad_calibration(frame_rows / own[:, None], own - 1.0).to_csv(tmp_path / run / "baseline" / "calibration.csv",
                                                                       index=False)
    a, b = (str(tmp_path / r / "baseline" / "calibration.csv") for r in "ab")
    raw = agreement.compare(pd.read_csv(a), pd.read_csv(b)).set_index(["channel", "parameter"])
    assert raw.loc[("gyro_x", "mis_pitch"), "difference"] == pytest.approx(-1080.0, abs=1.0)
    assert cli.main(["compare-campaigns", a, b]) == 0
    out = capsys.readouterr().out
    assert "B turned into A's body frame" in out and "+0, +0, +1080 arcsec" in out and "VERDICT: AGREE" in out


def test_the_walk_at_rest_is_the_white_rate_noise_times_the_root_of_the_interval():
    """White rate noise of sd 0.01 rad/s at 100 Hz walks 0.001 rad/sqrt(s) (ARW = sigma sqrt(dt))."""
    rng = np.random.default_rng(7)
    rate = rng.normal(0.0, 0.01, (12000, 3))
    assert rests.arw_at_rest(rate, 0.01, [(0, 6000), (9000, 12000)]) == pytest.approx(0.001, rel=0.15)
    assert rests.arw_at_rest(rate, 0.01, [(0, 500)]) is None


def test_a_maneuver_starts_at_its_first_valid_reference_sample_where_none_lies_before_and_the_report_says_so(tmp_path):
    """Motion capture that sees the markers only after 0.5 s (NaN rows 0-49 at 100 Hz): the first
    maneuver starts at row 50, not 0, and its start's attitude is the reference's there (it was refused:
    no valid sample brackets the start). The second starts at the rests' cut, a valid sample, as before;
    the end needs no sample of its own, so the NaN rows 2470-2499 leave it where it was."""
    from scipy.io import savemat

    from gyrocal.maneuvers.preprocess import slice_maneuver

    savemat(tmp_path / "trial_A.mat", broad_like(missing=tuple(range(50)) + tuple(range(2470, 2500))))
    out = tmp_path / "campaign"
    campaign, counts = importer.import_files("broad", out, [tmp_path / "trial_A.mat"], reference_interval_s=0)
    assert [(m.id, m.t_start, m.t_end) for m in campaign.maneuvers] == [
        ("trial_A_1", pytest.approx(0.5), pytest.approx(12.49)), ("trial_A_2", pytest.approx(12.5), pytest.approx(24.99))]
    assert counts["trial_A"]["trimmed"] == {"trial_A_1": 0.0}
    text = importer.report(campaign, counts, out)
    assert "trial_A_1 (free motion, 0.50 to 12.49 s; from its first valid reference sample, not 0.00 s)" in text
    first = slice_maneuver(telemetry.read_campaign(out), "trial_A_1")
    assert first.gyro_time[0] == pytest.approx(0.5)
    start = Rotation.from_quat(pd.read_csv(out / "star_tracker.csv").iloc[50][["q1", "q2", "q3", "q4"]].to_numpy(float))
    assert (Rotation.from_quat(first.attitude0_quat).inv() * start).magnitude() < 1e-12


def test_a_start_between_two_kept_reference_samples_stays_where_the_rests_cut(tmp_path):
    """At 0.1 s the kept rows are every tenth; a cut at row 1250 with row 1250 missing still has row 1240
    within one interval before it, so the second maneuver starts at the cut."""
    from scipy.io import savemat

    savemat(tmp_path / "trial_A.mat", broad_like(missing=(1250,)))
    campaign, counts = importer.build_campaign([tmp_path / "trial_A.mat"], importer.read_mapping("broad"), "c")
    assert campaign.maneuver("trial_A_2").t_start == pytest.approx(12.5) and counts["trial_A"]["trimmed"] == {}


def test_a_stretch_with_too_few_valid_reference_samples_is_left_out_and_named_and_a_file_without_any_refused(tmp_path):
    """Rows 0-1244 missing: the first stretch (rows 0-1249) keeps 5 valid samples, fewer than a maneuver
    needs (`telemetry.MIN_REFERENCE_SAMPLES`, as `slice_maneuver` asks), and is left out, not imported
    for validate to refuse the campaign over."""
    from scipy.io import savemat

    savemat(tmp_path / "trial_A.mat", broad_like(missing=tuple(range(1245))))
    campaign, counts = importer.build_campaign([tmp_path / "trial_A.mat"], importer.read_mapping("broad"), "c",
                                               reference_interval_s=0)
    assert [m.id for m in campaign.maneuvers] == ["trial_A_2"]
    assert counts["trial_A"]["left_out"] == [("trial_A_1", 0.0, pytest.approx(12.49))]
    assert "left out: trial_A_1 (0.00 to 12.49 s): fewer than 10 valid reference samples in it" in importer.report(
        campaign, counts, tmp_path)
    savemat(tmp_path / "trial_B.mat", broad_like(missing=tuple(range(2500))))
    with pytest.raises(InputError, match=r"trial_B\.mat.*no stretch of it has 10 valid reference samples kept \(0 in all"):
        importer.build_campaign([tmp_path / "trial_B.mat"], importer.read_mapping("broad"), "c", reference_interval_s=0)


def test_a_trial_that_turns_about_one_axis_while_it_shakes_about_another_is_labelled_by_the_turns(tmp_path):
    """Whole turns about y (1 rad/s for 10 s) while the wand shakes about x (3 rad/s at 5 Hz): the x
    gyro's rotations add up to more (19 rad against 10), but they go back and forth; the label follows
    the excursion (10 rad about y against 0.2 about x), the measure validate holds a label against."""
    n, dt = 1000, 0.01
    t = dt * np.arange(n)
    rate = np.column_stack([3.0 * np.sin(2 * np.pi * 5.0 * t), np.ones(n), np.zeros(n)])
    attitude = Rotation.identity()
    quat = [attitude.as_quat()]
    for k in range(1, n):
        attitude = attitude * Rotation.from_rotvec(0.5 * (rate[k] + rate[k - 1]) * dt)
        quat.append(attitude.as_quat())
    wxyz = np.array(quat)[:, [3, 0, 1, 2]]
    rows = np.column_stack([t, wxyz, np.full((n, 3), 9.81), rate, np.ones((n, 3))])
    header = "Time (s);Vicon Orientation;;;;IMU Acceleration;;;IMU Gyroscope;;;IMU Magnetometer;;;\n;W;X;Y;Z;X;Y;Z;X;Y;Z;X;Y;Z;\n"
    (tmp_path / "Shake_A.csv").write_text(header + "\n".join(";".join(f"{v:.10g}" for v in r) + ";" for r in rows) + "\n")
    campaign, _ = importer.build_campaign([tmp_path / "Shake_A.csv"], importer.read_mapping("repoimu"), "c")
    assert [(m.axis, m.direction) for m in campaign.maneuvers] == [("pitch", "both")]


def test_a_labelled_turn_across_a_reference_gap_is_checked_on_the_rest_and_accepted(tmp_path):
    """A turn about x at up to 2 rad/s whose reference is missing for 2 s at its fastest (200 dropped
    rows: the gyro turns about 220 deg across the gap, which the reference's rotation cannot show): the
    rotation check leaves the gap out (`sensing.comparable`) on a labelled maneuver as on a free one, and
    the gyro and reference, which agree, pass."""
    repoimu_like(tmp_path / "Trial_A.csv", rate_rad_s=2.0, n=3000, dropouts=range(650, 850))
    out = tmp_path / "campaign"
    importer.import_files("repoimu", out, [tmp_path / "Trial_A.csv"], reference_interval_s=0)
    assert cli.main(["validate", str(out)]) == 0


def test_a_stretch_is_imported_only_with_as_many_valid_samples_after_its_start_as_a_maneuver_needs(tmp_path):
    """Rows 0-1239 missing at 100 Hz: the first stretch (rows 0-1249) would start at row 1240 with nine
    valid samples after it, and `slice_maneuver` counts those after the start (the start's anchors the
    attitude): it is left out, not imported for validate to refuse the campaign over."""
    from scipy.io import savemat

    from gyrocal.maneuvers.preprocess import slice_maneuver

    savemat(tmp_path / "trial_A.mat", broad_like(missing=tuple(range(1240))))
    campaign, counts = importer.import_files("broad", tmp_path / "c", [tmp_path / "trial_A.mat"], reference_interval_s=0)
    assert [m.id for m in campaign.maneuvers] == ["trial_A_2"] and counts["trial_A"]["left_out"][0][0] == "trial_A_1"
    assert len(slice_maneuver(telemetry.read_campaign(tmp_path / "c"), "trial_A_2").st_time) > 1000


def still_reference(n, cross_rad, about_rad, boresight=(0.0, 0.0, 1.0), seed=3, at=(0.4, -1.1, 2.0)):
    """(n, 4) scalar-last quaternions of a body at rest at the attitude ``at`` (xyz Euler angles, rad), each
    sample off it by
    a body-frame white error of sd ``cross_rad`` about the two axes across ``boresight`` and ``about_rad``
    about it."""
    rng = np.random.default_rng(seed)
    b = np.asarray(boresight, dtype=float) / np.linalg.norm(boresight)
    u = np.cross(b, [1.0, 0.0, 0.0] if abs(b[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(b, u)
    error = (np.outer(rng.normal(0.0, cross_rad, n), u) + np.outer(rng.normal(0.0, cross_rad, n), v)
             + np.outer(rng.normal(0.0, about_rad, n), b))
    return (Rotation.from_euler("xyz", at) * Rotation.from_rotvec(error)).as_quat()


def test_the_reference_noise_at_rest_is_read_across_and_about_the_boresight():
    """A reference at rest with a white error of 40 arcsec across the boresight and 20 about it: the
    rotations between consecutive kept samples in the rests give both back (to a few %, from 8000 pairs),
    whichever axis is the boresight, with the differences' lag-1 correlation of white samples (-0.5); the
    motion between the rests and the rows not kept do not enter."""
    arcsec = np.pi / 180.0 / 3600.0
    for boresight in ((0.0, 0.0, 1.0), (1.0, 1.0, 0.0)):
        quat = still_reference(20000, 40 * arcsec, 20 * arcsec, boresight)
        quat[9000:11000] = Rotation.from_rotvec(np.outer(np.linspace(0, 3, 2000), [0, 1, 0])).as_quat()  # turning
        kept = np.zeros(20000, dtype=bool)
        kept[::2] = True
        found = rests.reference_noise_at_rest(quat, kept, [(0, 9000), (11000, 20000)], boresight)
        assert found.pairs == 8998 and found.white and found.lag1 == pytest.approx(-0.5, abs=0.03)
        assert found.cross_rad / arcsec == pytest.approx(40.0, rel=0.04)
        assert found.about_rad / arcsec == pytest.approx(20.0, rel=0.04)
    quat = still_reference(20000, 40 * arcsec, 20 * arcsec)
    across_x = rests.reference_noise_at_rest(quat, np.ones(20000, dtype=bool), [(0, 20000)], [1.0, 0.0, 0.0])
    assert across_x.cross_rad / arcsec == pytest.approx(np.sqrt((40**2 + 20**2) / 2), rel=0.04)
    assert across_x.about_rad / arcsec == pytest.approx(40.0, rel=0.04)


def test_a_reference_correlated_over_the_interval_kept_states_no_noise_at_rest():
    """The same white error averaged over 5 samples (a reference resampled above its cameras' rate) and kept
    at every sample: each difference is (w[k + 5] - w[k]) / 5, so it does not correlate with the next (white
    samples' do, -0.5) and understates the noise sqrt(5) times: not white, reported, not stated. Kept every
    5th sample it is white again."""
    arcsec = np.pi / 180.0 / 3600.0
    white = Rotation.from_quat(still_reference(20005, 40 * arcsec, 20 * arcsec, at=(0.0, 0.0, 0.0))).as_rotvec()
    smooth = np.mean([white[k:k + 20000] for k in range(5)], axis=0)  # sd 40 / sqrt(5) across
    quat = Rotation.from_rotvec(smooth).as_quat()
    every = rests.reference_noise_at_rest(quat, np.ones(20000, dtype=bool), [(0, 20000)], [0, 0, 1])
    assert every.lag1 == pytest.approx(0.0, abs=0.03) and not every.white
    assert every.cross_rad / arcsec == pytest.approx(40 / 5, rel=0.05)
    assert rests.pooled_reference_noise([every]) is None
    fifth = np.zeros(20000, dtype=bool)
    fifth[::5] = True
    apart = rests.reference_noise_at_rest(quat, fifth, [(0, 20000)], [0, 0, 1])
    assert apart.white and apart.cross_rad / arcsec == pytest.approx(40 / np.sqrt(5), rel=0.05)


def test_rests_too_short_or_a_reference_that_repeats_itself_state_no_reference_noise():
    quat = still_reference(400, 1e-4, 1e-4)
    kept = np.ones(400, dtype=bool)
    assert rests.reference_noise_at_rest(quat, kept, [(0, 200)], [0, 0, 1]) is None  # 199 pairs
    assert rests.reference_noise_at_rest(quat, kept, [(0, 201)], [0, 0, 1]).pairs == 200
    assert rests.reference_noise_at_rest(still_reference(400, 0.0, 0.0), kept, [(0, 400)], [0, 0, 1]) is None  # all held


def test_a_reference_held_at_its_last_pose_through_a_rest_is_no_quiet_reference():
    """A motion-capture system that holds its last pose (the same quaternion repeated) through the first of
    two rests: the held samples are no measurement, so the second rest alone states the 40 and 20 arcsec,
    where counting the repeats as differences of zero would halve them."""
    arcsec = np.pi / 180.0 / 3600.0
    quat = still_reference(4000, 40 * arcsec, 20 * arcsec)
    quat[:2000] = quat[0]
    found = rests.reference_noise_at_rest(quat, np.ones(4000, dtype=bool), [(0, 2000), (2000, 4000)], [0, 0, 1])
    assert found.pairs == 1999  # the live rest's; the held one has a single distinct sample
    assert found.cross_rad / arcsec == pytest.approx(40.0, rel=0.06) and found.about_rad / arcsec == pytest.approx(20.0, rel=0.06)


def test_several_recordings_state_their_rests_noise_pooled_by_pairs():
    """Two recordings' rests at 30 and 60 arcsec, 300 and 100 pairs: one level, the mean squares weighted by
    the pairs (sqrt((300 x 30^2 + 100 x 60^2) / 400) = 39.7), and a recording whose differences are not
    white left out."""
    arcsec = np.pi / 180.0 / 3600.0
    found = [rests.ReferenceAtRest(30 * arcsec, 15 * arcsec, 300, -0.5),
             rests.ReferenceAtRest(60 * arcsec, 30 * arcsec, 100, -0.5),
             rests.ReferenceAtRest(500 * arcsec, 500 * arcsec, 900, 0.4), None]
    cross, about = rests.pooled_reference_noise(found)
    assert cross / arcsec == pytest.approx(np.sqrt((300 * 30**2 + 100 * 60**2) / 400))
    assert about / arcsec == pytest.approx(np.sqrt((300 * 15**2 + 100 * 30**2) / 400))


def test_an_import_states_the_reference_noise_its_rests_show_unless_the_mapping_states_one(tmp_path):
    """BROAD's layout with an optical reference that scatters 30 arcsec across the body's z axis and 15
    about it at rest: campaign.yaml states that noise (the boresight it is split about beside it), as it
    states the gyro's ARW from the same rests, and the report prints it; a mapping that states a noise
    keeps its own."""
    from scipy.io import savemat

    arcsec = np.pi / 180.0 / 3600.0
    arrays = broad_like(n=6000, missing=(), motions=((2500, 3000),))
    turned = np.cumsum(np.r_[np.zeros(2500), np.ones(500), np.zeros(3000)]) / 100.0  # still at rest, not the gyro's walk
    error = Rotation.from_quat(still_reference(6000, 30 * arcsec, 15 * arcsec, at=(0.0, 0.0, 0.0)))
    arrays["opt_quat"] = (Rotation.from_rotvec(np.outer(turned, [1.0, 0.0, 0.0])) * error).as_quat()[:, [3, 0, 1, 2]]
    savemat(tmp_path / "trial_A.mat", arrays)
    out = tmp_path / "campaign"
    campaign, counts = importer.import_files("broad", out, [tmp_path / "trial_A.mat"])
    meta = yaml.safe_load((out / "campaign.yaml").read_text())["star_tracker"]
    assert meta["sigma_cross_arcsec"] == pytest.approx(30.0, rel=0.1)
    assert meta["sigma_about_arcsec"] == pytest.approx(15.0, rel=0.1)
    assert meta["boresight_body"] == [0.0, 0.0, 1.0] and meta["sigma_is"] == "white"
    assert "reference at rest: " in importer.report(campaign, counts, out)
    mapping = importer.read_mapping("broad")
    mapping["star_tracker"] = {"sigma_cross_arcsec": 60.0, "sigma_about_arcsec": 60.0}
    stated, _ = importer.build_campaign([tmp_path / "trial_A.mat"], mapping, "c")
    assert stated.star_tracker == {"sigma_cross_arcsec": 60.0, "sigma_about_arcsec": 60.0}
