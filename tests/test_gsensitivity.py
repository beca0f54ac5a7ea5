"""The library's g-sensitivity: a bias that follows the accelerometer's specific force."""

import numpy as np
import pandas as pd
import pytest

from gyrocal.inference.errormodel import effect_derivatives, view
from gyrocal.io.telemetry import read_campaign
from gyrocal.maneuvers.preprocess import slice_maneuver
from gyrocal.model import effects
from gyrocal.model.units import STANDARD_GRAVITY_M_S2
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.run import calibrate_campaign

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


@pytest.mark.full
def test_the_posterior_finds_a_known_g_sensitivity_and_no_other(tiny, tmp_path, config):
    mutations.corrupted_copy(tiny[0], tmp_path / "c", with_accelerometer)
    model = ["scale_factor", "misalignment", "bias", "g_sensitivity"]
    calibrate_campaign(tmp_path / "c", CampaignPaths.under(tmp_path / "out"), config_with(config, {"g": model}), ("g",))
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


@pytest.mark.full
def test_the_posterior_finds_a_known_gravity_offset_of_the_reference(tiny, tmp_path, config):
    mutations.corrupted_copy(tiny[0], tmp_path / "c", with_gravity_offset)
    model = ["scale_factor", "misalignment", "bias", "gravity_offset"]
    calibrate_campaign(tmp_path / "c", CampaignPaths.under(tmp_path / "out"), config_with(config, {"o": model}), ("o",))
    summary = pd.read_csv(tmp_path / "out" / "o" / "posterior_summary.csv", index_col=0)
    offset = summary[summary.index.str.startswith("gravity_offset.")]
    assert len(offset) == 6
    truth = np.where(offset.index == "gravity_offset.offset_roll_acc_z", OFFSET_ROLL_ACC_Z_ARCSEC_G, 0.0)
    z = (offset["mean"] - truth) / offset["sd"]
    assert np.abs(z).max() < 4.0
    assert offset.loc["gravity_offset.offset_roll_acc_z", "sd"] < OFFSET_ROLL_ACC_Z_ARCSEC_G / 5


def lab_scenario(tmp_path, **effects_given):
    """The tiny campaign on a rate table in a lab (`simulate`'s accelerometer), with these effects."""
    import yaml

    from conftest import DATA
    path = tmp_path / "lab.yaml"
    path.write_text(yaml.safe_dump({"base": str(DATA / "tiny.yaml"), "name": "tiny_lab",
                                    "accelerometer": {"gravity_m_s2": STANDARD_GRAVITY_M_S2},
                                    "effects": effects_given}))
    return path


def test_a_lab_campaign_logs_gravity_in_body_axes_turning_with_the_body(tmp_path):
    from gyrocal.simulation import simulate
    campaign, _ = simulate.simulate(simulate.load_scenario(lab_scenario(tmp_path)))
    force = np.column_stack([campaign.gyro_columns[f"acc_{a}"] for a in "xyz"])
    assert np.abs(np.linalg.norm(force, axis=1) - STANDARD_GRAVITY_M_S2).max() < 0.02
    roll = campaign.maneuver("roll_pos")
    during = (campaign.gyro_time >= roll.t_start) & (campaign.gyro_time <= roll.t_end)
    f = force[during]
    assert np.ptp(f[:, 0]) < 0.05  # a turn about x keeps the force's x part
    before, after = f[0, 1:], f[-1, 1:]  # and turns its y-z part by 90 degrees
    assert np.degrees(np.arccos(before @ after / np.linalg.norm(before) / np.linalg.norm(after))) == \
        pytest.approx(90.0, abs=1.0)


def test_an_effect_per_g_without_gravity_is_refused(tmp_path):
    import yaml

    from gyrocal.simulation import simulate

    from conftest import DATA
    path = tmp_path / "orbit.yaml"
    path.write_text(yaml.safe_dump({"base": str(DATA / "tiny.yaml"), "effects": {"g_sensitivity_deg_s_per_g": 0.01}}))
    with pytest.raises(ValueError, match=r"needs accelerometer\.gravity_m_s2"):
        simulate.load_scenario(path)


@pytest.mark.parametrize("effect,key,value,prefix", [
    ("g_sensitivity", "g_sensitivity_deg_s_per_g", 0.003, ".g_"),
    ("gravity_offset", "gravity_offset_arcsec_per_g", 600.0, "gravity_offset."),
])
@pytest.mark.full
def test_the_posterior_recovers_what_the_simulator_flew_per_g(tmp_path, config, effect, key, value, prefix):
    from gyrocal.simulation import simulate
    simulate.run(lab_scenario(tmp_path, **{key: value}), tmp_path / "sim")
    model = ["scale_factor", "misalignment", "bias", effect]
    calibrate_campaign(tmp_path / "sim/campaign", CampaignPaths.under(tmp_path / "out"), config_with(config, {"e": model}),
                       ("e",))
    summary = pd.read_csv(tmp_path / "out" / "e" / "posterior_summary.csv", index_col=0)
    coefficients = summary[summary.index.str.contains(prefix, regex=False)]
    assert len(coefficients) == (18 if effect == "g_sensitivity" else 6)
    z = (coefficients["mean"] - value) / coefficients["sd"]
    assert np.abs(z).max() < 4.0
    assert coefficients["sd"].max() < value / 4
