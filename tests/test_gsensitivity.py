"""The library's g-sensitivity: a bias that follows the accelerometer's specific force."""

import numpy as np
import pandas as pd
import pytest

from gyrocal import effects
from gyrocal.errormodel import effect_derivatives, view
from gyrocal.preprocess import slice_maneuver
from gyrocal.study import calibrate_steps
from gyrocal.telemetry import read_campaign
from gyrocal.units import STANDARD_GRAVITY_M_S2

import mutations
from conftest import config_with

G_Y_DEG_S_G = 0.003
"""dtg3_roll's true sensitivity to acc_y (11 deg/h/g, a DTG's mass unbalance)."""


def with_accelerometer(d):
    """The gyros turned and tilted: acc_y, acc_z follow a one-minute turn through gravity, acc_x
    a faster sway, and dtg3_roll senses ``G_Y_DEG_S_G`` of acc_y on top of its rate."""
    gyro = pd.read_csv(d / "gyro.csv")
    phase = 2 * np.pi * gyro["time"].to_numpy() / 60.0
    gyro["acc_x"] = 2.0 * np.sin(2 * np.pi * gyro["time"].to_numpy() / 17.0)
    gyro["acc_y"] = STANDARD_GRAVITY_M_S2 * np.sin(phase)
    gyro["acc_z"] = STANDARD_GRAVITY_M_S2 * np.cos(phase)
    dt = np.diff(gyro["time"].to_numpy(), prepend=gyro["time"].iloc[0])
    gyro["dtg3_roll"] += np.deg2rad(G_Y_DEG_S_G) / STANDARD_GRAVITY_M_S2 * gyro["acc_y"] * dt
    mutations._write(gyro, d, "gyro.csv")


def test_its_columns_are_the_specific_force_times_the_interval_on_every_channel(tiny, tmp_path):
    mutations.corrupted_copy(tiny[0], tmp_path / "c", with_accelerometer)
    campaign = read_campaign(tmp_path / "c")
    data = slice_maneuver(campaign, campaign.maneuvers[0].id)
    columns, _ = effect_derivatives(effects.LIBRARY["g_sensitivity"], view(data))
    assert sorted(columns) == ["g_x", "g_y", "g_z"]
    assert columns["g_y"].shape == data.increments.shape
    for j in range(len(data.channels)):
        assert np.array_equal(columns["g_y"][:, j], data.extras["acc_y"] * data.dt)


def test_without_accelerometer_columns_it_names_the_missing_one(tiny):
    data = slice_maneuver(read_campaign(tiny[0]), "yaw_pos")
    with pytest.raises(ValueError, match="g_sensitivity needs 'acc_x'"):
        effect_derivatives(effects.LIBRARY["g_sensitivity"], view(data))


def test_the_posterior_finds_a_known_g_sensitivity_and_no_other(tiny, tmp_path, config):
    mutations.corrupted_copy(tiny[0], tmp_path / "c", with_accelerometer)
    model = ["scale_factor", "misalignment", "bias", "g_sensitivity"]
    calibrate_steps(tmp_path / "c", tmp_path / "out", config_with(config, {"g": model}), ("g",))
    summary = pd.read_csv(tmp_path / "out" / "g" / "posterior_summary.csv", index_col=0)
    g = summary[summary.index.str.contains(r"\.g_[xyz]$")]
    assert len(g) == 18
    z = (g["mean"] - np.where(g.index == "dtg3_roll.g_y", G_Y_DEG_S_G, 0.0)) / g["sd"]
    assert np.abs(z).max() < 4.0
    assert g.loc["dtg3_roll.g_y", "sd"] < G_Y_DEG_S_G / 5


OFFSET_ROLL_ACC_Z_ARCSEC_G = 600.0
"""The reference's true attitude offset about roll per g of specific force along body z."""


def with_gravity_offset(d):
    """The accelerometer of `with_accelerometer`, the gyros without g-sensitivity, and a reference
    that sits ``OFFSET_ROLL_ACC_Z_ARCSEC_G`` per g of acc_z off about roll (a mount that sags)."""
    from scipy.spatial.transform import Rotation
    gyro = pd.read_csv(d / "gyro.csv")
    phase = 2 * np.pi * gyro["time"].to_numpy() / 60.0
    gyro["acc_x"] = 2.0 * np.sin(2 * np.pi * gyro["time"].to_numpy() / 17.0)
    gyro["acc_y"] = STANDARD_GRAVITY_M_S2 * np.sin(phase)
    gyro["acc_z"] = STANDARD_GRAVITY_M_S2 * np.cos(phase)
    mutations._write(gyro, d, "gyro.csv")
    st = pd.read_csv(d / "star_tracker.csv")
    offset_rad = np.deg2rad(OFFSET_ROLL_ACC_Z_ARCSEC_G / 3600) * np.cos(2 * np.pi * st["time"].to_numpy() / 60.0)
    columns = ["q1", "q2", "q3", "q4"]
    turned = Rotation.from_quat(st[columns].to_numpy()) * Rotation.from_rotvec(
        np.column_stack([offset_rad, np.zeros_like(offset_rad), np.zeros_like(offset_rad)]))
    st[columns] = turned.as_quat()
    mutations._write(st, d, "star_tracker.csv")


def test_the_posterior_finds_a_known_gravity_offset_of_the_reference(tiny, tmp_path, config):
    mutations.corrupted_copy(tiny[0], tmp_path / "c", with_gravity_offset)
    model = ["scale_factor", "misalignment", "bias", "gravity_offset"]
    calibrate_steps(tmp_path / "c", tmp_path / "out", config_with(config, {"o": model}), ("o",))
    summary = pd.read_csv(tmp_path / "out" / "o" / "posterior_summary.csv", index_col=0)
    offset = summary[summary.index.str.startswith("gravity_offset.")]
    assert len(offset) == 6
    truth = np.where(offset.index == "gravity_offset.offset_roll_acc_z", OFFSET_ROLL_ACC_Z_ARCSEC_G, 0.0)
    z = (offset["mean"] - truth) / offset["sd"]
    assert np.abs(z).max() < 4.0
    assert offset.loc["gravity_offset.offset_roll_acc_z", "sd"] < OFFSET_ROLL_ACC_Z_ARCSEC_G / 5
