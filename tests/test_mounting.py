"""A reference sensor whose frame is not the body frame: declared, estimated, or refused."""

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


def test_a_nominal_mounting_far_off_is_refined_by_the_data(tiny, tmp_path):
    _, findings = checks.read_checked(mounted(tiny, tmp_path, [0.0, 0.0, 0.0, 1.0]))
    assert findings.mounting["source"] == "nominal, refined by the data's alignment"
    estimated = Rotation.from_quat(findings.mounting["quat"])
    assert np.rad2deg((estimated * MOUNTING.inv()).magnitude()) * 3600 < 60.0


def test_the_report_says_what_an_estimated_mounting_leaves_unidentified():
    from gyrocal.report.review import mounting_text
    text = mounting_text({"quat": [0, 0, 0, 1], "source": "estimated from the data", "angle_deg": 2.855,
                          "sd_deg": {"roll": 0.1, "pitch": 0.2, "yaw": 0.1}})
    assert "2.855 deg" in text and "Everything is relative" in text and "non-orthogonality" in text
    assert "Everything is relative" not in mounting_text({"quat": [0, 0, 0, 1], "source": "nominal (campaign.yaml)",
                                                          "angle_deg": 1.0})
