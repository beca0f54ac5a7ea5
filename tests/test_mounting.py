"""A reference sensor whose frame is not the body frame: declared, estimated, or refused."""

import json

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy.spatial.transform import Rotation

from gyrocal import checks
from gyrocal.io.telemetry import TelemetryError

import mutations

MOUNTING = Rotation.from_rotvec(np.deg2rad([1.5, -2.0, 1.0]))
"""The reference frame's attitude in body axes: 2.7 deg, as far as the RepoIMU Vicon frame sits."""


def mounted(tiny, tmp_path, declared):
    def turn(d):
        st = pd.read_csv(d / "star_tracker.csv")
        ok = st["valid"] == 1
        q = Rotation.from_quat(st.loc[ok, ["q1", "q2", "q3", "q4"]].to_numpy()) * MOUNTING
        st.loc[ok, ["q1", "q2", "q3", "q4"]] = q.as_quat()
        st.to_csv(d / "star_tracker.csv", index=False, float_format="%.17g")
        if declared is not None:
            meta = yaml.safe_load((d / "campaign.yaml").read_text())
            meta["star_tracker"]["mounting"] = declared
            (d / "campaign.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    directory = tmp_path / "campaign"
    mutations.corrupted_copy(tiny[0], directory, turn)
    return directory


def test_an_undeclared_mounting_is_refused_pointing_at_the_mounting(tiny, tmp_path):
    with pytest.raises(TelemetryError, match="mounting"):
        checks.read_checked(mounted(tiny, tmp_path, None))


def test_an_estimated_mounting_recovers_the_true_one(tiny, tmp_path):
    _, findings = checks.read_checked(mounted(tiny, tmp_path, "estimate"))
    estimated = Rotation.from_quat(findings.mounting["quat"])
    assert findings.mounting["source"] == "estimated from the data"
    assert np.rad2deg((estimated * MOUNTING.inv()).magnitude()) * 3600 < 60.0


def test_a_nominal_mounting_is_applied_as_declared(tiny, tmp_path):
    _, findings = checks.read_checked(mounted(tiny, tmp_path, MOUNTING.as_quat().tolist()))
    assert findings.mounting["source"] == "nominal (campaign.yaml)"
    assert findings.mounting["angle_deg"] == pytest.approx(np.rad2deg(MOUNTING.magnitude()))


def test_a_declared_mounting_far_off_is_refused_never_replaced_saying_what_to_write(tiny, tmp_path):
    with pytest.raises(TelemetryError) as refused:
        checks.read_checked(mounted(tiny, tmp_path, [0.0, 0.0, 0.0, 1.0]))
    message = str(refused.value)
    assert "star_tracker.mounting, applied as declared, leaves the reference turned from the gyros by 2.688 deg" in message
    assert "(about roll +1.504, pitch -1.998, yaw +0.985 deg)" in message
    assert "No other common convention of it fits either" in message
    corrected = Rotation.from_quat(eval(message.split("the data's alignment, mounting: ")[1].split("]")[0] + "]"))
    assert np.rad2deg((corrected * MOUNTING.inv()).magnitude()) * 3600 < 60.0   # what to write, to an arcminute
    assert "mounting: estimate" in message


@pytest.mark.parametrize("convention, fits", [
    (lambda q: MOUNTING.inv().as_quat(), "its conjugate (the inverse convention"),
    (lambda q: np.roll(MOUNTING.as_quat(), 1), "it read scalar first"),
])
def test_a_mounting_in_another_convention_is_refused_naming_the_one_that_fits(tiny, tmp_path, convention, fits):
    with pytest.raises(TelemetryError) as refused:
        checks.read_checked(mounted(tiny, tmp_path, convention(None).tolist()))
    message = str(refused.value)
    assert fits[0].upper() + fits[1:] in message
    written = eval(message.split(fits[1:])[1].split("write mounting: ")[1].split("]")[0] + "]")
    assert Rotation.from_quat(written).approx_equal(MOUNTING, atol=1e-6)


def test_misalignments_the_bound_allows_are_carried_not_refused():
    from gyrocal.checks.mounting import carried
    bound = np.deg2rad(1.0)
    assert carried(Rotation.from_rotvec(np.deg2rad([0.9, -0.9, 0.5])), [0.01] * 3, bound)
    assert not carried(Rotation.from_rotvec(np.deg2rad([1.2, 0.0, 0.0])), [0.01] * 3, bound)
    assert carried(Rotation.from_rotvec(np.deg2rad([1.2, 0.0, 0.0])), [0.05] * 3, bound)   # within 5 sd of it


def test_the_report_says_what_an_estimated_mounting_leaves_unidentified():
    from gyrocal.report.review import mounting_text
    text = mounting_text({"quat": [0, 0, 0, 1], "source": "estimated from the data", "angle_deg": 2.855,
                          "sd_deg": {"roll": 0.1, "pitch": 0.2, "yaw": 0.1}})
    assert "2.855 deg" in text and "Everything is relative" in text and "non-orthogonality" in text
    assert "Everything is relative" not in mounting_text({"quat": [0, 0, 0, 1], "source": "nominal (campaign.yaml)",
                                                          "angle_deg": 1.0})


LARGE = {  # 0.5 to 0.9 deg: as large as the small-angle model of eq. 3 carries, far above the prior's sd
    "dtg2_yaw": {"sf_pos": 800, "sf_neg": -300, "mis_roll": 2900, "mis_pitch": -2200},
    "dtg3_yaw": {"sf_pos": -1200, "sf_neg": 150, "mis_roll": -1900, "mis_pitch": 3000},
    "dtg1_roll": {"sf_pos": 1500, "sf_neg": 900, "mis_yaw": 3100, "mis_pitch": 1900},
    "dtg3_roll": {"sf_pos": -600, "sf_neg": -1100, "mis_yaw": -2500, "mis_pitch": -3200},
    "dtg1_pitch": {"sf_pos": 300, "sf_neg": 1300, "mis_yaw": -2600, "mis_roll": 3200},
    "dtg2_pitch": {"sf_pos": -900, "sf_neg": 400, "mis_yaw": 2100, "mis_roll": -1800},
}


@pytest.mark.full
def test_large_misalignments_under_a_declared_mounting_are_estimated_not_absorbed(tmp_path, config):
    """The case that once ended in a GO with the misalignments near zero: a triad misaligned by
    0.5-0.9 deg, behind a reference mounted 2.7 deg off body axes and declared so."""
    from gyrocal.simulation import simulate

    from conftest import DATA, config_with, run_campaign
    scenario = yaml.safe_load((DATA / "tiny.yaml").read_text())
    scenario.update(name="misaligned", truth=LARGE)
    (tmp_path / "misaligned.yaml").write_text(yaml.safe_dump(scenario))
    simulate.run(tmp_path / "misaligned.yaml", tmp_path / "sim")
    directory = mounted((tmp_path / "sim" / "campaign", None), tmp_path, MOUNTING.as_quat().tolist())
    run_campaign(directory, tmp_path / "out", config_with(config, {"baseline": ["scale_factor", "misalignment", "bias"]}))
    table = pd.read_csv(tmp_path / "out" / "baseline" / "calibration.csv").set_index(["channel", "parameter"])
    truth = pd.Series({(c, p): v for c, values in LARGE.items() for p, v in values.items()})
    rows = table.loc[truth.index]
    inside = (rows["ci95_low"] <= truth) & (truth <= rows["ci95_high"])
    assert inside.sum() >= 22, rows[~inside]
    misalignments = [k for k in truth.index if k[1].startswith("mis_")]
    assert np.all(np.abs(rows.loc[misalignments, "mean"] - truth[misalignments]) < 30.0)   # arcsec, of 1800-3200
    info = json.loads((tmp_path / "out" / "input.json").read_text())
    assert info["mounting"]["source"] == "nominal (campaign.yaml)"
    assert max(abs(v) for v in info["mounting"]["residual_deg"].values()) < 0.9
    assert json.loads((tmp_path / "out" / "verdict.json").read_text())["verdict"] == "GO"
