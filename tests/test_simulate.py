"""The simulator against the physics: the key check of the foundation."""

import hashlib

import numpy as np
import pytest

from gyrocal.inference.fit.classic import hold_windows
from gyrocal.io import telemetry
from gyrocal.maneuvers import preprocess
from gyrocal.model import channels as ch
from gyrocal.model.units import AXIS_INDEX, arcsec_to_rad, arw_to_rad_sqrt_s, rad_to_arcsec
from gyrocal.pipeline import cli
from gyrocal.simulation import simulate

from conftest import DATA, truth_vector


def file_hashes(directory):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(directory.iterdir())}


def test_same_seed_same_files_other_seed_other_files(tmp_path):
    for name, seed in (("a", 3), ("b", 3), ("c", 4)):
        assert cli.main(["simulate", str(DATA / "tiny.yaml"), str(tmp_path / name), "--seed", str(seed)]) == 0
    a, b, c = (file_hashes(tmp_path / n / "campaign") for n in "abc")
    assert a == b
    assert a["gyro.csv"] != c["gyro.csv"]
    assert (tmp_path / "a" / "truth.json").read_text() == (tmp_path / "b" / "truth.json").read_text()



def test_the_fine_grid_in_blocks_gives_the_same_campaign(monkeypatch):
    """The simulator walks its fine truth grid in blocks to bound memory: the block size changes no number."""
    scenario = simulate.load_scenario(DATA / "tiny.yaml")
    scenario["effects"].update(temperature_swing_K=5.0, sf_nonlinearity_ppm_per_deg2_s2=20.0, bias_drift_deg_h_per_h=0.01)
    whole, _ = simulate.simulate(scenario)
    monkeypatch.setattr(simulate, "GYRO_BLOCK", 37)
    blocks, _ = simulate.simulate(scenario)
    assert list(blocks.gyro_columns) == list(whole.gyro_columns) and "temp_dtg1" in whole.gyro_columns
    for name, column in whole.gyro_columns.items():
        assert np.array_equal(blocks.gyro_columns[name], column), name
    assert np.array_equal(blocks.st_quat, whole.st_quat) and np.array_equal(blocks.st_valid, whole.st_valid)

def test_default_scenario_takes_the_papers_tables_as_truth(mom):
    truth = mom[1]["parameters"]
    assert truth["dtg2_yaw"]["sf_pos"] == -1712 and truth["dtg3_yaw"]["sf_neg"] == -603
    assert truth["dtg3_roll"]["sf_neg"] == 253 and truth["dtg1_pitch"]["sf_neg"] == -46
    assert truth["dtg2_yaw"]["mis_roll"] == 133 and truth["dtg3_yaw"]["mis_pitch"] == 90
    assert truth["dtg1_roll"]["mis_yaw"] == -124 and truth["dtg3_roll"]["mis_pitch"] == 95
    assert truth["dtg1_pitch"]["mis_yaw"] == -67 and truth["dtg2_pitch"]["mis_roll"] == -56


@pytest.fixture(scope="module")
def mom_maneuvers(mom):
    campaign = telemetry.read_campaign(mom[0])
    return campaign, [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]


def test_with_true_parameters_removed_the_error_is_at_the_noise_level(mom, mom_maneuvers):
    """RMS within 10 % of what the star tracker and the gyro random walk predict."""
    campaign, maneuvers = mom_maneuvers
    truth = truth_vector(campaign.channels, mom[1])
    st = campaign.star_tracker
    b = np.asarray(st["boresight_body"])
    cov = (arcsec_to_rad(st["sigma_cross_arcsec"]) ** 2 * (np.eye(3) - np.outer(b, b))
           + arcsec_to_rad(st["sigma_about_arcsec"]) ** 2 * np.outer(b, b))
    q = arw_to_rad_sqrt_s(campaign.gyro["arw_deg_sqrt_h"]) ** 2
    squares, predicted = [], []
    for data in maneuvers:
        params = truth.subset([c.name for c in data.channels])
        for channel_set in data.sets:
            err = preprocess.error_angles(data, channel_set, params)
            squares.append(np.mean(err**2))
            # the measurement's noise, the start attitude's noise, and the accumulated walk
            predicted.append(2 * np.trace(cov) / 3 + q * np.mean(data.st_time - data.gyro_time[0]))
    ratio = np.sqrt(np.mean(squares) / np.mean(predicted))
    assert abs(ratio - 1) < 0.10, ratio


def closed_form_end_error(axis, angle, sf, mis_b, mis_c):
    """Error at the end of an ideal rotation about ``axis`` by ``angle`` (rad) caused by the
    rotated channel's scale factor and the other channels' misalignment toward ``axis``."""
    a = AXIS_INDEX[axis]
    b, c = (a + 1) % 3, (a + 2) % 3
    e = np.zeros(3)
    e[a] = -sf * angle
    e[b] = -mis_b * np.sin(angle) - mis_c * (1 - np.cos(angle))
    e[c] = mis_b * (1 - np.cos(angle)) - mis_c * np.sin(angle)
    return e


def rotations(maneuvers, truth):
    """Per maneuver and channel set: its hold masks and the closed-form end error."""
    for data in maneuvers:
        before, after = hold_windows(data)
        a = AXIS_INDEX[data.axis]
        b, c = (a + 1) % 3, (a + 2) % 3
        angle = np.deg2rad(90.0) * (1 if data.direction == "+" else -1)
        for channel_set in data.sets:
            sub = truth.subset(channel_set)
            sf = sub.sf_pos[a] if angle > 0 else sub.sf_neg[a]
            expected = closed_form_end_error(data.axis, angle, sf, sub.mis_rad[b, a], sub.mis_rad[c, a])
            yield data, channel_set, before, after, expected


def bias_only(truth):
    n = len(truth.channels)
    return ch.ChannelParams(truth.channels, np.zeros(n), np.zeros(n), np.zeros((n, 3)), truth.bias_rad_s)


def test_with_parameters_left_in_the_end_error_is_scale_factor_and_misalignment_times_angle(mom, mom_maneuvers):
    """Per maneuver and channel set: the error that the scale factor and misalignments leave
    after the rotation (noise cancels: same data propagated with and without them)."""
    campaign, maneuvers = mom_maneuvers
    truth = truth_vector(campaign.channels, mom[1])
    for data, channel_set, before, after, expected in rotations(maneuvers, truth):
        left_in = preprocess.error_angles(data, channel_set, bias_only(truth))
        removed = preprocess.error_angles(data, channel_set, truth)
        effect = (left_in - removed)[after].mean(axis=0) - (left_in - removed)[before].mean(axis=0)
        # second-order terms (scale factor times misalignment times angle) stay below 1.5"
        assert np.allclose(rad_to_arcsec(effect), rad_to_arcsec(expected), atol=1.5), (data.id, channel_set)


def test_end_error_with_noise_matches_within_the_noise(mom, mom_maneuvers):
    """The raw nominal error at the end hold, bias removed, against the closed form."""
    campaign, maneuvers = mom_maneuvers
    truth = truth_vector(campaign.channels, mom[1])
    sigma_walk = rad_to_arcsec(arw_to_rad_sqrt_s(0.003)) * np.sqrt(1500.0)
    for data, channel_set, before, after, expected in rotations(maneuvers, truth):
        observed = preprocess.end_of_rotation_error(data, channel_set, bias_only(truth), before, after)
        assert np.all(np.abs(rad_to_arcsec(observed - expected)) < 4 * sigma_walk + 5), (data.id, channel_set)
