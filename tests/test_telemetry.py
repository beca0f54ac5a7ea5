import shutil

import numpy as np
import pandas as pd
import pytest
import yaml

from gyrocal.io import telemetry
from gyrocal.io.telemetry import TelemetryError
from gyrocal.pipeline import cli


@pytest.fixture
def campaign_copy(tiny, tmp_path):
    directory = tmp_path / "campaign"
    shutil.copytree(tiny[0], directory)
    return directory


def edit_csv(path, change):
    frame = pd.read_csv(path, **telemetry.READ_CSV_EXACT)
    frame = change(frame)
    frame.to_csv(path, index=False, float_format="%.17g")


def edit_yaml(path, change):
    meta = yaml.safe_load(path.read_text())
    change(meta)
    path.write_text(yaml.safe_dump(meta, sort_keys=False))


def test_write_read_round_trip_is_exact(tiny, tmp_path):
    original = telemetry.read_campaign(tiny[0])
    telemetry.write_campaign(original, tmp_path / "again")
    again = telemetry.read_campaign(tmp_path / "again")
    assert again.name == original.name == "tiny"
    assert again.maneuvers == original.maneuvers
    assert np.array_equal(again.st_quat, original.st_quat)
    assert np.array_equal(again.increments(), original.increments())
    assert np.array_equal(again.st_valid, original.st_valid)
    assert again.star_tracker == original.star_tracker


def test_validate_cli_prints_a_summary(tiny, capsys):
    assert cli.main(["validate", str(tiny[0])]) == 0
    lines = capsys.readouterr().out.splitlines()
    campaign = telemetry.read_campaign(tiny[0])
    invalid = int((campaign.st_valid == 0).sum())
    assert lines[0] == "campaign tiny: OK"
    assert lines[1] == "  channels   " + ", ".join(campaign.channel_names)
    assert lines[3].startswith(f"  gyro       {len(campaign.gyro_time)} rows at 5 Hz")
    assert lines[4].startswith(f"  star trk   {len(campaign.st_time)} rows at 1 Hz, {invalid} flagged invalid")
    assert lines[6] == "  maneuvers  6"
    assert [line.split()[0] for line in lines[7:]] == [m.id for m in campaign.maneuvers]


def test_invalid_star_tracker_rows_are_counted_not_refused(tiny):
    campaign = telemetry.read_campaign(tiny[0])
    assert (campaign.st_valid == 0).sum() == round(0.005 * len(campaign.st_time))


def expect(directory, pattern):
    with pytest.raises(TelemetryError, match=pattern):
        telemetry.read_campaign(directory)


def test_missing_column_is_named(campaign_copy):
    edit_csv(campaign_copy / "gyro.csv", lambda f: f.drop(columns=["dtg3_yaw"]))
    expect(campaign_copy, r"gyro\.csv: missing column\(s\) \['dtg3_yaw'\]")


def test_nan_names_line_and_column(campaign_copy):
    def poke(f):
        f.loc[41, "dtg1_pitch"] = np.nan
        return f
    edit_csv(campaign_copy / "gyro.csv", poke)
    expect(campaign_copy, r"gyro\.csv: line 43, column 'dtg1_pitch': value is NaN")


def test_a_truncated_row_is_called_short_not_nan(campaign_copy):
    path = campaign_copy / "gyro.csv"
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    lines[42] = ",".join(lines[42].split(",")[:3])
    path.write_text("\n".join(lines) + "\n")
    expect(campaign_copy, rf"gyro\.csv: line 43 has 3 of the header's {len(header)} fields \(a short or truncated "
                          rf"row\): column '{header[3]}' has no value")


def test_time_going_backwards_names_the_line(campaign_copy):
    def poke(f):
        f.loc[100, "time"] = f.loc[98, "time"]
        return f
    edit_csv(campaign_copy / "star_tracker.csv", poke)
    expect(campaign_copy, r"star_tracker\.csv: line 102, column 'time': time .* does not increase")


def test_non_unit_quaternion_names_the_line(campaign_copy):
    def poke(f):
        row = int(np.flatnonzero(f["valid"].to_numpy() == 1)[10])
        f.loc[row, "q1"] += 0.01
        poke.line = row + 2
        return f
    edit_csv(campaign_copy / "star_tracker.csv", poke)
    expect(campaign_copy, rf"line {poke.line}, columns q1..q4: quaternion norm is")


def test_maneuver_outside_the_data_is_refused(campaign_copy):
    edit_yaml(campaign_copy / "campaign.yaml", lambda m: m["maneuvers"][-1].update(t_end=1e7))
    expect(campaign_copy, r"campaign\.yaml: maneuver pitch_neg: .* lies outside the data")


def test_unknown_channel_in_gyro_csv_is_refused(campaign_copy):
    edit_csv(campaign_copy / "gyro.csv", lambda f: f.assign(dtg4_yaw=0.0))
    expect(campaign_copy, r"\['dtg4_yaw'\] look like gyro channels but campaign\.yaml does not declare")


def test_unknown_in_loop_channel_is_refused(campaign_copy):
    edit_yaml(campaign_copy / "campaign.yaml", lambda m: m["maneuvers"][0].update(in_loop=["dtg9_yaw"]))
    expect(campaign_copy, r"maneuvers\[0\] \(yaw_pos\)\.in_loop: unknown channel 'dtg9_yaw'")


def test_a_valid_flag_other_than_0_or_1_names_the_line(campaign_copy):
    def poke(f):
        f.loc[30, "valid"] = 2
        return f
    edit_csv(campaign_copy / "star_tracker.csv", poke)
    expect(campaign_copy, r"star_tracker\.csv: line 32, column 'valid': must be 0 or 1")


def test_a_bad_direction_names_the_maneuver(campaign_copy):
    edit_yaml(campaign_copy / "campaign.yaml", lambda m: m["maneuvers"][1].update(direction="up"))
    expect(campaign_copy, r"campaign\.yaml: maneuvers\[1\] \(yaw_neg\)\.direction: must be \"\+\", \"-\" or both, got 'up'")


def test_non_numeric_cell_is_named(campaign_copy):
    def poke(f):
        f["q2"] = f["q2"].astype(object)
        f.loc[5, "q2"] = "oops"
        return f
    edit_csv(campaign_copy / "star_tracker.csv", poke)
    expect(campaign_copy, r"line 7, column 'q2': not a number: 'oops'")


def test_write_is_whole_or_nothing(tiny, tmp_path, monkeypatch):
    campaign = telemetry.read_campaign(tiny[0])

    def broken(*args, **kwargs):
        raise OSError("disk full")
    monkeypatch.setattr(pd.DataFrame, "to_csv", broken)
    with pytest.raises(OSError):
        telemetry.write_campaign(campaign, tmp_path / "out")
    assert not (tmp_path / "out").exists()
    assert list(tmp_path.iterdir()) == []


def test_unpaired_channel_is_refused_with_the_reason(campaign_copy):
    edit_yaml(campaign_copy / "campaign.yaml", lambda m: m["channels"].pop("dtg3_roll"))
    edit_csv(campaign_copy / "gyro.csv", lambda f: f.drop(columns=["dtg3_roll"]))
    expect(campaign_copy, r"campaign\.yaml: channels: every body axis needs the same number of gyro channels")


def test_noise_groups_default_to_one_for_the_campaign_and_round_trip(campaign_copy, tmp_path):
    from gyrocal.maneuvers import preprocess

    assert {m.noise_group for m in telemetry.read_campaign(campaign_copy).maneuvers} == {"all"}
    assert "noise_group" not in (campaign_copy / "campaign.yaml").read_text()
    edit_yaml(campaign_copy / "campaign.yaml",
              lambda meta: [m.update(noise_group="quiet" if i % 2 else "loud") for i, m in enumerate(meta["maneuvers"])])
    campaign = telemetry.read_campaign(campaign_copy)
    telemetry.write_campaign(campaign, tmp_path / "again")
    again = telemetry.read_campaign(tmp_path / "again")
    assert again.maneuvers == campaign.maneuvers
    names, index = preprocess.noise_groups(again.maneuvers)
    assert names == ["loud", "quiet"]
    assert index.tolist() == [0, 1, 0, 1, 0, 1]
    data = preprocess.slice_maneuver(again, again.maneuvers[1].id)
    data.save(tmp_path / "m.npz")
    assert preprocess.ManeuverData.load(tmp_path / "m.npz").noise_group == "quiet"


def test_a_bad_noise_group_is_refused_naming_the_file_and_maneuver(campaign_copy, capsys):
    edit_yaml(campaign_copy / "campaign.yaml", lambda m: m["maneuvers"][1].update(noise_group="trial 1"))
    expect(campaign_copy, r"campaign\.yaml.*maneuvers\[1\] \(yaw_neg\)\.noise_group")
    assert cli.main(["validate", str(campaign_copy)]) != 0
    assert "noise_group" in capsys.readouterr().err


def test_a_reference_interval_keeps_every_kth_sample_and_counts_the_rest(tiny):
    """``reference_interval_s`` keeps each maneuver's first star-tracker sample, every k-th after it
    (k = interval / median step) and its last; the ones left out are counted, not dropped silently."""
    from gyrocal.maneuvers import preprocess

    campaign = telemetry.read_campaign(tiny[0])
    m = campaign.maneuvers[0].id
    every = preprocess.slice_maneuver(campaign, m)
    step = float(np.median(np.diff(every.st_time)))
    thinned = preprocess.slice_maneuver(campaign, m, reference_interval_s=3 * step)
    expected = np.r_[every.st_time[::3], every.st_time[-1:]] if (len(every.st_time) - 1) % 3 else every.st_time[::3]
    np.testing.assert_array_equal(thinned.st_time, expected)
    np.testing.assert_array_equal(thinned.st_quat, every.st_quat[np.isin(every.st_time, expected)])
    assert thinned.counts["st_thinned"] == len(every.st_time) - len(expected) and every.counts["st_thinned"] == 0
    assert thinned.counts["st_used"] + thinned.counts["st_thinned"] == every.counts["st_used"]
    np.testing.assert_array_equal(thinned.increments, every.increments)
    with pytest.raises(telemetry.TelemetryError, match=r"maneuver .* has only \d+ valid samples kept every "
                                                       r"reference_interval_s = "):
        preprocess.slice_maneuver(campaign, m, reference_interval_s=every.st_time[-1] - every.st_time[0])
