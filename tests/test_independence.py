"""The verdict's warning where maneuvers are closer in time than the star tracker's error remembers."""

from types import SimpleNamespace

import numpy as np
import pytest

from gyrocal.checks.finding import Status
from gyrocal.criticism.independence import gap_check, gaps


def maneuver(name, start, stop):
    return SimpleNamespace(id=name, st_time=np.arange(start, stop + 1.0), noise_group="campaign")


CAMPAIGN = [maneuver("b", 340, 640), maneuver("a", 0, 320), maneuver("c", 1040, 1340)]


def test_gaps_run_from_one_maneuvers_last_reference_sample_to_the_next_ones_first_in_time_order():
    assert gaps(CAMPAIGN) == [("a", "b", 20.0), ("b", "c", 400.0)]


def test_white_noise_has_no_check_and_long_gaps_pass():
    assert gap_check(CAMPAIGN, None) is None
    quick = gap_check(CAMPAIGN, 3.0)
    assert quick.status is Status.PASS and quick.figure == pytest.approx(np.exp(-20 / 3))


def test_a_gap_under_three_correlation_times_warns_naming_the_pair_and_the_spacing_to_fly():
    finding = gap_check(CAMPAIGN, 30.0)
    assert finding.status is Status.WARN and finding.passed
    assert finding.figure == pytest.approx(np.exp(-20 / 30))
    assert finding.where == "a, b" and "1 of 2 gaps" in finding.why
    assert finding.action == "fly maneuvers at least 90 s apart (3 correlation times)"


def test_maneuvers_of_different_noise_groups_are_separate_recordings_and_never_warn():
    """`gyrocal import` puts each file in its own noise group, one sample after the last: no warning."""
    trials = [SimpleNamespace(id=f"trial{k}", st_time=np.arange(100.0 * k, 100.0 * k + 99.0), noise_group=f"file{k}")
              for k in range(3)]
    assert gaps(trials) == []
    assert gap_check(trials, 30.0).status is Status.PASS
    same = [SimpleNamespace(**{**vars(t), "noise_group": "one"}) for t in trials]
    assert gap_check(same, 30.0).status is Status.WARN
