"""Property: whatever happens to the bytes of a campaign's files, gyrocal's reading and checking of
it ends in success or in one `gyrocal.errors.InputError` naming the file; never another exception.

Hypothesis edits the tiny campaign's text: it deletes, repeats or truncates lines, puts odd
characters (a comma, a colon, an anchor, a tab, a NaN, a huge number) into campaign.yaml,
star_tracker.csv or gyro.csv, replaces a CSV value by an extreme one (1e300, -1e308, inf, an
empty field) or by its mantissa (a lost exponent), and saves a file in UTF-16, with a byte-order
mark or with another separator, one to three edits at a time.
"""

import shutil
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import yaml
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from gyrocal import checks
from gyrocal.errors import InputError
from gyrocal.io.telemetry import TelemetryError
from gyrocal.model import effects

from conftest import ROOT
from mutations import corrupted_copy

FILES = st.sampled_from(["campaign.yaml", "star_tracker.csv", "gyro.csv"])
TEXT = st.sampled_from([",", ":", "-", ".", "e", "\t", " ", "&a", "*a", "[", "{", "nan", "1e300", "-0", "'", "\n",
                        "name: x", "valid", "q1"])
EDITS = st.one_of(
    st.tuples(st.just("delete_line"), FILES, st.integers(0, 10**6)),
    st.tuples(st.just("repeat_line"), FILES, st.integers(0, 10**6)),
    st.tuples(st.just("truncate"), FILES, st.floats(0.0, 1.0)),
    st.tuples(st.just("insert"), FILES, st.integers(0, 10**7), TEXT),
    st.tuples(st.just("replace_char"), FILES, st.integers(0, 10**7), TEXT),
    st.tuples(st.just("replace_field"), st.sampled_from(["star_tracker.csv", "gyro.csv"]), st.integers(0, 10**7),
              st.sampled_from(["1e300", "-1e308", "nan", "inf", "0", "1e-300", "", "2", "-1"])),
    st.tuples(st.just("lose_exponent"), st.sampled_from(["star_tracker.csv", "gyro.csv"]), st.integers(0, 10**7)),
    st.tuples(st.just("encode"), FILES, st.integers(0, 0), st.sampled_from(["utf-16", "utf-8-sig", ";", "\t"])),
)


def edit(directory, operation):
    """One edit of a campaign file's text, in place."""
    kind, name, where, *text = operation
    path = directory / name
    try:
        content = path.read_text()
    except UnicodeDecodeError:  # saved in UTF-16 by an earlier edit: left so
        return
    lines = content.splitlines(keepends=True)
    if kind in ("delete_line", "repeat_line") and not lines:
        return
    if kind == "delete_line":
        del lines[where % len(lines)]
        content = "".join(lines)
    elif kind == "repeat_line":
        k = where % len(lines)
        lines.insert(k, lines[k])
        content = "".join(lines)
    elif kind == "replace_field":
        k = 1 + where % (len(lines) - 1)
        fields = lines[k].rstrip("\n").split(",")
        fields[(where // len(lines)) % len(fields)] = text[0]
        lines[k] = ",".join(fields) + "\n"
        content = "".join(lines)
    elif kind == "lose_exponent":  # a cell written without its exponent: 9.84e-05 as 9.84
        k = 1 + where % (len(lines) - 1)
        fields = lines[k].rstrip("\n").split(",")
        j = (where // len(lines)) % len(fields)
        fields[j] = fields[j].lower().split("e")[0]
        lines[k] = ",".join(fields) + "\n"
        content = "".join(lines)
    elif kind == "encode":  # saved as a spreadsheet might: UTF-16, a byte-order mark, another separator
        if text[0] in ("utf-16", "utf-8-sig"):
            path.write_bytes(content.encode(text[0]))
            return
        content = content.replace(",", text[0]) if name.endswith(".csv") else content
    elif kind == "truncate":
        content = content[:int(where * len(content))]
    else:
        k = where % max(len(content), 1)
        content = content[:k] + text[0] + content[k + (kind == "replace_char"):]
    path.write_text(content)


@settings(max_examples=150, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(operations=st.lists(EDITS, min_size=1, max_size=3))
@example(operations=[("replace_field", "gyro.csv", 10876, "1e300")])  # an impossible value mid-turn
@example(operations=[("lose_exponent", "gyro.csv", 1250 + 10001 * 3)])  # dtg2_yaw mid-turn of yaw_pos
@example(operations=[("encode", "star_tracker.csv", 0, "utf-16")])
@example(operations=[("encode", "gyro.csv", 0, ";")])
def test_any_edit_of_the_files_ends_in_success_or_a_refusal_naming_the_file(operations, tiny, tmp_path_factory):
    directory = tmp_path_factory.mktemp("edited") / "campaign"
    shutil.copytree(tiny[0], directory)
    for operation in operations:
        edit(directory, operation)
    try:
        checks.read_checked(directory)
        event("accepted")
    except InputError as refused:
        event(f"refused: {type(refused).__name__}")
        assert str(directory) in str(refused), str(refused)


def refused(tiny, tmp_path, mutate, block_s=None) -> str:
    """The refusal of a mutated copy of the tiny campaign, as `gyrocal validate` words it."""
    with pytest.raises(TelemetryError) as error:
        checks.read_checked(corrupted(tiny, tmp_path, mutate), block_s=block_s)
    return str(error.value)


def corrupted(tiny, tmp_path, mutate):
    corrupted_copy(tiny[0], tmp_path / "c", mutate)
    return tmp_path / "c"


def edit_csv(name, change):
    def mutate(d):
        frame = pd.read_csv(d / name)
        change(frame)
        frame.to_csv(d / name, index=False, float_format="%.17g")
    return mutate


def edit_lines(name, change):
    def mutate(d):
        lines = (d / name).read_text().splitlines()
        change(lines)
        (d / name).write_text("\n".join(lines) + "\n")
    return mutate


def mid_turn_row(d, maneuver=0):
    """The gyro.csv row (0 for the first data row) half-way through a maneuver."""
    m = yaml.safe_load((d / "campaign.yaml").read_text())["maneuvers"][maneuver]
    time = pd.read_csv(d / "gyro.csv")["time"].to_numpy()
    return int(np.searchsorted(time, (m["t_start"] + m["t_end"]) / 2))


def test_every_reference_sample_invalid_is_refused_naming_the_column(tiny, tmp_path):
    message = refused(tiny, tmp_path, edit_csv("star_tracker.csv", lambda f: f.__setitem__("valid", 0)))
    assert "star_tracker.csv: column 'valid': no sample is valid" in message


def test_a_directory_where_gyro_csv_belongs_is_refused(tiny, tmp_path):
    def mutate(d):
        (d / "gyro.csv").unlink()
        (d / "gyro.csv").mkdir()
    assert "gyro.csv: is not a file (a directory?)" in refused(tiny, tmp_path, mutate)


@pytest.mark.parametrize("change, said", [
    (lambda lines: lines.__setitem__(0, lines[0] + ","), "line 1: column 8 of the header has no name"),
    (lambda lines: lines.insert(300, lines[0]), "line 301: repeats the header (two files joined?)"),
    (lambda lines: lines.__setitem__(0, lines[0].replace("dtg2_yaw", "dtg1_roll")),
     "the header names column(s) ['dtg1_roll'] more than once"),
])
def test_header_faults_are_refused_naming_the_line(tiny, tmp_path, change, said):
    assert said in refused(tiny, tmp_path, edit_lines("gyro.csv", change))


def test_an_impossible_gyro_value_mid_turn_is_refused_and_one_outside_every_maneuver_is_a_warning(tiny, tmp_path):
    def inside(d):
        frame = pd.read_csv(d / "gyro.csv")
        frame.loc[mid_turn_row(d), "dtg2_yaw"] = 1e300
        frame.to_csv(d / "gyro.csv", index=False, float_format="%.17g")
    message = refused(tiny, tmp_path / "inside", inside)
    assert "dtg2_yaw = 1e+300 rad): an increment faster than any gyro senses (100 rad/s) inside a maneuver" in message
    outside = corrupted(tiny, tmp_path / "outside", edit_csv("gyro.csv", lambda f: f.loc.__setitem__((2, "dtg1_roll"), 1e308)))
    _, findings = checks.read_checked(outside)
    assert any("line 4 (dtg1_roll = 1e+308 rad)" in w and "outside every maneuver" in w for w in findings.warnings)


def test_a_redundant_channel_with_its_sign_flipped_is_refused_naming_it(tiny, tmp_path):
    message = refused(tiny, tmp_path, edit_csv("gyro.csv", lambda f: f.__setitem__("dtg1_roll", -f["dtg1_roll"])))
    assert "channels dtg1_roll+dtg2_pitch+dtg3_yaw: channel dtg1_roll turns opposite to the star tracker" in message
    assert "its sign is flipped" in message


def test_times_in_milliseconds_are_refused_naming_the_unit(tiny, tmp_path):
    def milliseconds(d):
        for name in ("gyro.csv", "star_tracker.csv"):
            edit_csv(name, lambda f: f.__setitem__("time", f["time"] * 1000))(d)
        meta = yaml.safe_load((d / "campaign.yaml").read_text())
        for m in meta["maneuvers"]:
            m["t_start"], m["t_end"] = m["t_start"] * 1000, m["t_end"] * 1000
        (d / "campaign.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    message = refused(tiny, tmp_path, milliseconds)
    assert "the median step between gyro samples is 200 s: times in milliseconds? (x 1e-3: a 0.2 s step)" in message


def test_a_gyro_read_less_often_than_the_reference_is_refused(tiny, tmp_path):
    def sparse(d):
        frame = pd.read_csv(d / "gyro.csv")
        kept = frame.iloc[::10].copy()
        columns = [c for c in frame.columns if c != "time"]
        kept[columns] = frame[columns].rolling(10).sum().iloc[::10].fillna(frame[columns].iloc[0]).to_numpy()
        kept.to_csv(d / "gyro.csv", index=False, float_format="%.17g")
    message = refused(tiny, tmp_path, sparse)
    assert "the gyro is read every 2 s (median), the star tracker every 1 s" in message



def declare_rates(gyro_hz=None, st_hz=None):
    """A mutation that declares sampling rates in campaign.yaml."""
    def mutate(d):
        meta = yaml.safe_load((d / "campaign.yaml").read_text())
        for section, rate in (("gyro", gyro_hz), ("star_tracker", st_hz)):
            if rate is not None:
                meta[section] = {**(meta.get(section) or {}), "rate_hz": rate}
        (d / "campaign.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    return mutate


def test_declared_sampling_rates_that_the_data_keep_pass(tiny, tmp_path):
    campaign, findings = checks.read_checked(corrupted(tiny, tmp_path, declare_rates(gyro_hz=5, st_hz=1.0)))
    assert campaign.gyro["rate_hz"] == 5 and campaign.star_tracker["rate_hz"] == 1.0
    assert not findings.errors


@pytest.mark.parametrize("gyro_hz, st_hz, expected", [
    (10, None, "gyro.csv: the median step between samples is 0.2 s (5 Hz), but campaign.yaml declares gyro: "
               "{rate_hz: 10}, a 0.1 s step"),
    (None, 2, "star_tracker.csv: the median step between samples is 1 s (1 Hz), but campaign.yaml declares "
              "star_tracker: {rate_hz: 2}, a 0.5 s step"),
])
def test_data_sampled_otherwise_than_declared_are_refused_naming_the_file(tiny, tmp_path, gyro_hz, st_hz, expected):
    message = refused(tiny, tmp_path, declare_rates(gyro_hz, st_hz))
    assert expected in message and ".rate_hz" in message


def test_a_declared_rate_must_be_a_positive_number(tiny, tmp_path):
    with pytest.raises(InputError, match="rate_hz"):
        checks.read_checked(corrupted(tiny, tmp_path, declare_rates(gyro_hz=-5)))

def test_a_latency_of_one_gyro_sample_is_a_warning(tiny, tmp_path):
    late = corrupted(tiny, tmp_path, edit_csv("star_tracker.csv", lambda f: f.__setitem__("time", f["time"] + 0.2)))
    _, findings = checks.read_checked(late)
    clock = [w for w in findings.warnings if "line up best when the gyro clock is shifted by" in w]
    assert len(clock) >= 4, findings.warnings


def test_a_maneuver_shorter_than_the_posteriors_blocks_takes_shorter_ones_and_one_too_short_for_any_is_refused(
        tiny, tmp_path):
    checks.read_checked(tiny[0], block_s=400.0)
    message = refused(tiny, tmp_path, edit_csv("star_tracker.csv", lambda f: f.__setitem__(
        "valid", np.where((f["time"] % 200.0) < 190.0, 0, f["valid"]))), block_s=400.0)
    assert "too short for the leave-one-block-out predictive (blocks of sampler.block_s = 400 s, halved" in message


def test_validate_into_a_closed_pipe_ends_quietly(tiny):
    run = subprocess.run(f"{sys.executable} -m gyrocal.pipeline.cli validate {tiny[0]} | head -1", shell=True,
                         capture_output=True, text=True, check=False, cwd=ROOT)
    assert run.stdout.startswith("campaign tiny: OK") and run.stderr == ""


def test_a_step_prints_a_refusal_and_exits_1_without_a_traceback(tmp_path, capsys):
    from gyrocal.pipeline.steps import common
    (tmp_path / "bad.py").write_text("x = 1\n")
    with pytest.raises(SystemExit) as stop, common.refusal():
        effects.load_plugins([tmp_path / "bad.py"])
    assert "gyrocal: the campaign was refused:" in str(stop.value) and "must define EFFECTS" in str(stop.value)
