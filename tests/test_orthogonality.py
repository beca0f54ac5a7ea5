"""The channel sets' non-orthogonality (issue 42): the angles between sensing axes, against a dense
reference (three known vectors, turned), on the MOM layout's two sets, and on a simulated
campaign's posterior (orthogonality.csv covers the truth)."""

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from gyrocal.model import channels as ch
from gyrocal.model import orthogonality as orth
from gyrocal.model.spec import baseline
from gyrocal.model.units import AXES, rad_to_arcsec

TRIAD = [ch.Channel("gyro_x", None, "roll"), ch.Channel("gyro_y", None, "pitch"), ch.Channel("gyro_z", None, "yaw")]


def skewed_triad(d_xy, d_xz, d_yz) -> np.ndarray:
    """Rows: three unit vectors near x, y, z whose angles are 90 deg less d_xy, d_xz, d_yz (rad),
    built directly from the angles."""
    x = np.array([1.0, 0.0, 0.0])
    y = np.array([np.sin(d_xy), np.cos(d_xy), 0.0])
    a = np.sin(d_xz)
    b = (np.sin(d_yz) - a * np.sin(d_xy)) / np.cos(d_xy)
    z = np.array([a, b, np.sqrt(1 - a * a - b * b)])
    return np.array([x, y, z])


def misalignments_of(rows: np.ndarray) -> np.ndarray:
    """The model's misalignments (rad) of sensing directions ``rows`` (any length): each row over
    its own-axis component (the length goes to the scale factor), that component dropped."""
    mis = rows / np.diag(rows)[:, None]
    mis[np.arange(3), np.arange(3)] = 0.0
    return mis


def spec_values(spec, mis_rad: np.ndarray) -> np.ndarray:
    """A spec's parameter vector (units) holding the misalignments (rad) of gyro_x, gyro_y, gyro_z."""
    values = np.zeros(len(spec))
    for c, channel in enumerate(TRIAD):
        for b, axis in enumerate(AXES):
            if axis != channel.axis:
                values[spec.index(f"{channel.name}.mis_{axis}")] = rad_to_arcsec(mis_rad[c, b])
    return values


def test_a_turned_skewed_triad_gives_its_known_angles_whatever_the_turn():
    """Three axes 300, -150 and 80 arcsec off orthogonal, turned 0.4 deg about an oblique axis: the
    misalignments change by the turn (by hundreds of arcsec), the non-orthogonality does not, and it
    equals the known angles to 1e-6 arcsec; m_ab + m_ba gives them to second order only (0.5 arcsec
    unturned, 5 arcsec turned: the square of 0.4 deg is 10 arcsec), hence the exact angle."""
    known = np.array([300.0, -150.0, 80.0])  # xy, xz, yz, arcsec
    rows = skewed_triad(*np.deg2rad(known / 3600))
    spec = baseline(TRIAD)
    pairs = orth.pairs(spec, [("gyro_x", "gyro_y", "gyro_z")])
    assert [p.name for p in pairs] == ["nonorth_roll_pitch", "nonorth_roll_yaw", "nonorth_pitch_yaw"]
    assert pairs[0].definition == "gyro_x.mis_pitch + gyro_y.mis_roll"
    turn = Rotation.from_rotvec(np.deg2rad(0.4) * np.array([0.6, -0.48, 0.64]))
    for matrix, second_order in ((rows, 0.5), (rows @ turn.as_matrix().T, 5.0)):
        mis = misalignments_of(matrix)
        got = orth.pair_draws(spec_values(spec, mis), spec, pairs)
        assert got == pytest.approx(known, abs=1e-6)
        first_order = rad_to_arcsec([mis[0, 1] + mis[1, 0], mis[0, 2] + mis[2, 0], mis[1, 2] + mis[2, 1]])
        assert first_order == pytest.approx(known, abs=second_order)
        assert np.abs(first_order - known).max() > 1e-3
    moved = rad_to_arcsec(misalignments_of(rows @ turn.as_matrix().T) - misalignments_of(rows))
    assert np.abs(moved).max() > 500


def test_a_pure_turn_of_an_orthogonal_triad_has_no_non_orthogonality_and_draws_keep_their_shape():
    """Misalignments that are only a turn of the triad (antisymmetric, m_ab = -m_ba, of 1000 arcsec)
    give zero to second order; a (2, 5, P) stack of draws gives (2, 5, 3)."""
    spec = baseline(TRIAD)
    pairs = orth.pairs(spec, [("gyro_x", "gyro_y", "gyro_z")])
    mis = misalignments_of(Rotation.from_rotvec(np.deg2rad([0.2, -0.3, 0.25])).as_matrix())
    assert np.abs(orth.pair_draws(spec_values(spec, mis), spec, pairs)).max() < 1e-6
    stack = np.broadcast_to(spec_values(spec, mis), (2, 5, len(spec)))
    assert orth.pair_draws(stack, spec, pairs).shape == (2, 5, 3)


def test_mom_layout_gives_three_pairs_per_channel_set_each_once():
    """The MOM channels in two sets (selected, redundant): six pairs, none within one axis, none twice;
    a model without misalignments has none."""
    spec = baseline(ch.MOM_CHANNELS)
    sets = ch.channel_sets(ch.MOM_CHANNELS, ("dtg1_roll", "dtg2_pitch", "dtg2_yaw"))
    pairs = orth.pairs(spec, sets + sets[:1])
    assert [p.label for p in pairs] == [
        "dtg1_roll+dtg2_pitch.nonorth_roll_pitch", "dtg1_roll+dtg2_yaw.nonorth_roll_yaw",
        "dtg2_pitch+dtg2_yaw.nonorth_pitch_yaw", "dtg3_roll+dtg1_pitch.nonorth_roll_pitch",
        "dtg3_roll+dtg3_yaw.nonorth_roll_yaw", "dtg1_pitch+dtg3_yaw.nonorth_pitch_yaw"]
    assert {p.set for p in pairs} == {"dtg1_roll+dtg2_pitch+dtg2_yaw", "dtg3_roll+dtg1_pitch+dtg3_yaw"}
    no_mis = type(spec)("bias_only", spec.channels, [p for p in spec.parameters if not p.name.startswith("mis_")],
                        ["scale_factor", "bias"])
    assert orth.pairs(no_mis, sets) == []


@pytest.fixture(scope="module")
def short_run(tiny_short_run):
    return tiny_short_run[0]


def test_on_a_simulated_campaign_orthogonality_csv_covers_the_true_angles(tiny, short_run):
    """The tiny campaign (six DTG channels in two sets, every misalignment informed): each of the six
    pairs' 95 % interval holds the truth's non-orthogonality (the sum's; their difference, a sign
    slip, would fall outside: 110, 20, -25 arcsec on the first set); the point is m_ab + m_ba of
    calibration.csv's points to second order."""
    spec = baseline(ch.MOM_CHANNELS)
    truth = np.zeros(len(spec))
    for name, values in tiny[1]["parameters"].items():
        for key, value in values.items():
            if key.startswith("mis_"):
                truth[spec.index(f"{name}.{key}")] = value
    table = pd.read_csv(short_run / "baseline/orthogonality.csv")
    assert list(table["set"].unique()) == ["dtg3_roll+dtg1_pitch+dtg2_yaw", "dtg1_roll+dtg2_pitch+dtg3_yaw"]
    assert len(table) == 6 and not table["prior_only"].any()
    pairs = orth.pairs(spec, [tuple(s.split("+")) for s in table["set"].unique()])
    assert [p.name for p in pairs] == table["parameter"].tolist()
    true_angle = orth.pair_draws(truth, spec, pairs)
    assert np.abs(true_angle).min() > 10  # the truth is not orthogonal: the test can tell
    assert ((table["ci95_low"] <= true_angle) & (true_angle <= table["ci95_high"])).all(), table
    cal = pd.read_csv(short_run / "baseline/calibration.csv").set_index(["channel", "parameter"])
    for p, row in zip(pairs, table.itertuples(), strict=True):
        (a, b), (i, j) = p.axes, p.channels
        first_order = cal.loc[(i, f"mis_{b}"), "point"] + cal.loc[(j, f"mis_{a}"), "point"]
        assert row.point == pytest.approx(first_order, abs=0.5)
        assert row.definition == f"{i}.mis_{b} + {j}.mis_{a}"
