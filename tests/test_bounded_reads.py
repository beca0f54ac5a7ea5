"""Reads are bounded and refusals short: a campaign file far larger than its rate and maneuvers
need is refused before it is read, an echoed cell is cut, a file saved in UTF-16 or with another
separator says how to save it, and extra gyro.csv columns hold plausible readings."""

import shutil

import pytest

from gyrocal import checks
from gyrocal.errors import InputError
from gyrocal.io import telemetry


def copy(tiny, tmp_path):
    directory = tmp_path / "campaign"
    shutil.copytree(tiny[0], directory)
    return directory


def refused(directory):
    with pytest.raises(InputError) as err:
        checks.read_checked(directory)
    return str(err.value)


def test_a_gyro_file_beyond_what_its_rate_and_maneuvers_need_is_refused_before_reading(tiny, tmp_path):
    directory = copy(tiny, tmp_path)
    with open(directory / "gyro.csv", "r+b") as handle:  # sparse: 300 MiB on paper, no disk
        handle.truncate(300 * 2**20)
    message = refused(directory)
    assert "gyro.csv: is 0.29 GiB, more than a campaign needs: at 5 Hz over the maneuvers' span and 6 h either " \
           "side (45160 s) it holds at most 256 MiB" in message


def test_a_file_within_the_floor_is_read_whole(tiny):
    limit, rate, span = telemetry.size_cap(tiny[0] / "gyro.csv", None, telemetry.read_meta(tiny[0])["maneuvers"])
    assert limit == telemetry.READ_FLOOR_BYTES and rate == pytest.approx(5.0) and span == pytest.approx(45160.0)


def test_an_8_mb_cell_is_named_not_echoed(tiny, tmp_path):
    directory = copy(tiny, tmp_path)
    lines = (directory / "gyro.csv").read_text().splitlines()
    cells = lines[5].split(",")
    cells[2] = "x" * 8_000_000
    lines[5] = ",".join(cells)
    (directory / "gyro.csv").write_text("\n".join(lines) + "\n")
    message = refused(directory)
    assert "line 6, column 'dtg1_pitch': not a number: 'xxxx" in message
    assert "... (8000000 characters)" in message
    assert len(message) < 300


def test_a_star_tracker_file_in_utf16_says_save_it_as_utf8(tiny, tmp_path):
    directory = copy(tiny, tmp_path)
    path = directory / "star_tracker.csv"
    path.write_bytes(path.read_text().encode("utf-16"))
    message = refused(directory)
    assert message.endswith("star_tracker.csv: line 1: is UTF-16 text (a byte-order mark or NUL bytes at its start), "
                            "not UTF-8. Save it as UTF-8 (in a spreadsheet: CSV UTF-8, comma-separated)")


def test_a_star_tracker_file_separated_by_semicolons_says_save_it_comma_separated(tiny, tmp_path):
    directory = copy(tiny, tmp_path)
    path = directory / "star_tracker.csv"
    path.write_text(path.read_text().replace(",", ";"))
    message = refused(directory)
    assert "star_tracker.csv: line 1: separates its columns with ';', not commas: 'time;q1;q2;q3;q4;valid'. " \
           "Save it comma-separated" in message


@pytest.mark.parametrize("value", ["1e300", "-1e300", "1e13"])
def test_an_extra_column_beyond_any_reading_is_refused_naming_line_and_column(tiny, tmp_path, value):
    directory = copy(tiny, tmp_path)
    lines = (directory / "gyro.csv").read_text().splitlines()
    lines[0] += ",temperature_c"
    lines[1:] = [line + ",20.5" for line in lines[1:]]
    lines[40] = lines[40].rsplit(",", 1)[0] + "," + value
    (directory / "gyro.csv").write_text("\n".join(lines) + "\n")
    message = refused(directory)
    assert f"gyro.csv: line 41, column 'temperature_c': {float(value):.6g} is larger than any reading a regressor " \
           "can use (1e+12; 1 such row(s))" in message
