"""A campaign-wide convention fault gives one finding that names it, before the per-maneuver physics;
files whose clocks do not overlap are refused naming the offset, not the maneuvers."""

import numpy as np
import pandas as pd
import pytest

from gyrocal import checks
from gyrocal.errors import InputError

from mutations import corrupted_copy, gyro_scale, scalar_first


def conjugated(d):
    st = pd.read_csv(d / "star_tracker.csv")
    st[["q1", "q2", "q3"]] *= -1
    st.to_csv(d / "star_tracker.csv", index=False, float_format="%.17g")


def gyro_offset(seconds):
    def mutate(d):
        gy = pd.read_csv(d / "gyro.csv")
        gy["time"] += seconds
        gy.to_csv(d / "gyro.csv", index=False, float_format="%.17g")
    return mutate


def refused(tiny, tmp_path, mutate):
    corrupted_copy(tiny[0], tmp_path / "c", mutate)
    with pytest.raises(InputError) as err:
        checks.read_checked(tmp_path / "c")
    return str(err.value)


@pytest.mark.parametrize("mutate, said", [
    (conjugated, "star_tracker.csv, columns q1..q4, lines 2-2001: the quaternions look conjugated"),
    (scalar_first, "star_tracker.csv, columns q1..q4, lines 2-2001: the quaternions look scalar first"),
    (gyro_scale(180 / np.pi), "increments in degrees rather than radians?"),
    (gyro_scale(1e3), "increments 1000 times too large"),
])
def test_a_systematic_convention_fault_is_one_finding_that_names_it(tiny, tmp_path, mutate, said):
    message = refused(tiny, tmp_path, mutate)
    assert "(1 finding(s))" in message, message
    assert said in message
    assert "(6 of 6" in message


def test_files_whose_times_do_not_overlap_are_refused_naming_the_offset(tiny, tmp_path):
    message = refused(tiny, tmp_path, gyro_offset(100000.0))
    assert "gyro.csv: column 'time': its times [101000.2, 103000] s and star_tracker.csv's [1000, 2999] s do not " \
           "overlap: gyro.csv starts 98001.2 s after star_tracker.csv ends" in message
    assert "campaign.yaml" not in message
