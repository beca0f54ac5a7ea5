"""Dead, stuck and frozen sensors and single corrupt gyro cells are refused before any fit, naming
the file, the column, the lines and the likely cause; clean simulated campaigns are not flagged."""

import pytest

from gyrocal import checks
from gyrocal.errors import InputError
from gyrocal.simulation import simulate

from conftest import DATA
from mutations import corrupted_copy, frozen_reference, lost_exponent, stuck_channel


def refusal(tiny, tmp_path, mutate):
    directory = tmp_path / "campaign"
    where = corrupted_copy(tiny[0], directory, mutate)
    with pytest.raises(InputError) as err:
        checks.read_checked(directory)
    return str(err.value), where


def test_a_channel_reading_zero_through_the_roll_maneuvers_is_refused_naming_its_lines(tiny, tmp_path):
    message, (first, last) = refusal(tiny, tmp_path, stuck_channel("dtg1_roll", ("roll_pos", "roll_neg")))
    assert "(1 finding(s))" in message
    assert f"gyro.csv, column 'dtg1_roll', lines {first}-{last}: reads exactly 0" in message
    assert "roll_pos: +90 deg, read +0 deg; roll_neg: -90 deg, read +0 deg" in message
    assert "a dead or stuck channel" in message


def test_a_channel_stuck_at_a_constant_through_one_turn_is_refused(tiny, tmp_path):
    message, (first, last) = refusal(tiny, tmp_path, stuck_channel("dtg2_pitch", ("pitch_pos",), 3e-6))
    assert f"column 'dtg2_pitch', lines {first}-{last}: reads the constant 3e-06 rad" in message
    assert "pitch_pos: +90 deg" in message


def test_a_reference_that_repeats_its_attitude_while_the_gyros_turn_is_refused_as_frozen(tiny, tmp_path):
    message, (first, last) = refusal(tiny, tmp_path, frozen_reference(20.0))
    assert "(1 finding(s))" in message
    assert f"star_tracker.csv, columns q1..q4, lines {first}-{last}: the attitude repeats exactly for 20 samples" in message
    assert "a frozen reference" in message and "valid = 0" in message


def test_a_gyro_cell_that_lost_its_exponent_is_refused_naming_line_and_column(tiny, tmp_path):
    message, line = refusal(tiny, tmp_path, lost_exponent("dtg2_yaw"))
    assert "(1 finding(s))" in message
    assert f"gyro.csv, line {line}, column 'dtg2_yaw'" in message
    assert "lost its exponent" in message and "about 1e3" in message


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_clean_simulated_campaigns_are_not_flagged(seed, tmp_path):
    simulate.run(DATA / "tiny.yaml", tmp_path, seed=seed)
    _, findings = checks.read_checked(tmp_path / "campaign")
    assert not [f for f in findings.items if f.check in ("stuck", "frozen", "spike")]


def test_a_channel_dead_across_its_axis_is_refused_by_the_run_its_noise_never_makes(tiny, tmp_path):
    """dtg2_pitch reads 0 through the roll maneuvers, where only its misalignment toward roll turns it:
    the reference cannot tell, but 3200 repeats of one value are beyond its noise."""
    message, (first, last) = refusal(tiny, tmp_path, stuck_channel("dtg2_pitch", ("roll_pos", "roll_neg")))
    assert f"column 'dtg2_pitch', lines {first}-{last}: reads exactly 0 for 3200 samples" in message
    assert "inside maneuver(s) roll_pos, roll_neg, where its own noise elsewhere repeats a value that long by " \
           "chance once in 1e" in message
