"""The classic method with each channel set's residual bias estimated from the inertial holds."""

import numpy as np
import pytest

from gyrocal.inference.fit import classic
from gyrocal.maneuvers import preprocess
from gyrocal.model import spec
from gyrocal.model.units import rad_s_to_deg_h
from gyrocal.simulation import simulate

from conftest import DATA

BIAS_DEG_H = {"dtg3_roll": 0.2, "dtg1_roll": -0.25, "dtg1_pitch": -0.15, "dtg2_pitch": 0.3,
              "dtg2_yaw": 0.25, "dtg3_yaw": -0.2}
"""Deliberately large residual biases, distinct per channel and of both signs (the sign and the
channel each estimate lands on are then checked)."""

BIAS_SD_DEG_H = 0.013
"""Sd of a hold-estimated bias on this scenario (300 s holds; 20 seeds: 0.009 roll, 0.009 pitch,
0.013 yaw, which lies mostly about the star tracker's boresight)."""


def campaign(biases):
    """The tiny scenario with 300 s holds, one maneuver per axis and the given biases (deg/h);
    the same seed, so the noise is the same whatever the biases."""
    scenario = simulate.load_scenario(DATA / "tiny.yaml")
    scenario["maneuver_defaults"]["hold_s"] = 300.0
    scenario["maneuvers"] = [m for m in scenario["maneuvers"] if m["id"] in ("yaw_pos", "roll_neg", "pitch_pos")]
    for name, bias in biases.items():
        scenario["truth"][name] = {**scenario["truth"][name], "bias_deg_h": bias}
    sim, truth = simulate.simulate(scenario)
    return [preprocess.slice_maneuver(sim, m.id) for m in sim.maneuvers], truth


@pytest.fixture(scope="module")
def biased():
    return campaign(BIAS_DEG_H)


@pytest.fixture(scope="module")
def unbiased():
    return campaign(dict.fromkeys(BIAS_DEG_H, 0.0))


def tables(maneuvers, truth):
    """Both variants' tables with the truth and each one's error, in the parameters' units."""
    base = spec.baseline(maneuvers[0].channels)
    paper, holds = (classic.classic_table(maneuvers, base, b).set_index(["channel", "parameter"])
                    for b in ("trusted", "holds"))
    truth_values = np.array([truth["parameters"][c][p] for c, p in paper.index])
    return paper.assign(err=paper["value"] - truth_values), holds.assign(err=holds["value"] - truth_values)


def test_hold_bias_is_the_channels_bias_with_its_sign(biased):
    maneuvers, truth = biased
    names = [c.name for c in maneuvers[0].channels]
    errors = []
    for data in maneuvers:
        before, after = classic.hold_windows(data)
        for channel_set in data.sets:
            params = classic.hold_bias(data, channel_set, before, after)
            index = [names.index(n) for n in channel_set]
            others = np.setdiff1d(np.arange(len(names)), index)
            assert np.all(params.bias_rad_s[others] == 0.0)
            assert not params.sf_pos.any() and not params.sf_neg.any() and not params.mis_rad.any()
            est = rad_s_to_deg_h(params.bias_rad_s[index])
            errors.append(est - [truth["parameters"][n]["bias_deg_h"] for n in channel_set])
    errors = np.array(errors)
    assert errors.shape == (6, 3)
    assert np.abs(errors).max() < 4 * BIAS_SD_DEG_H                # measured: 0.017 deg/h at most
    assert np.sqrt(np.mean(errors**2)) < 1.5 * BIAS_SD_DEG_H        # measured: 0.0085


def test_holds_variant_removes_the_scale_factor_error_of_the_bias(biased):
    maneuvers, truth = biased
    paper, holds = tables(maneuvers, truth)
    sf = paper.index.get_level_values("parameter").str.startswith("sf")
    assert sf.sum() == 6 and (paper["unit"] == holds["unit"]).all()
    # The paper reads the bias's drift between the holds' centres (490 s apart) over the 90 deg
    # turn as a scale factor: 0.1 deg/h -> 151 ppm, signed by the bias and the turn's direction.
    channels = paper.index.get_level_values("channel")[sf]
    turn_deg = np.where(paper.index.get_level_values("parameter")[sf] == "sf_pos", 90.0, -90.0)
    expected = np.array([BIAS_DEG_H[c] for c in channels]) / 3600.0 * 490.0 / turn_deg / 1e-6
    assert np.abs(paper["err"][sf] - expected).max() < 40          # measured: 14 ppm at most
    assert np.abs(paper["err"][sf]).min() > 200                    # measured: 220 to 445 ppm
    assert np.abs(holds["err"][sf]).max() < 40                     # measured: 28 ppm at most
    rms = [np.sqrt(np.mean(t["err"][sf] ** 2)) for t in (paper, holds)]
    assert rms[1] < 0.1 * rms[0]                                   # measured: 16 and 346 ppm
    assert np.abs(holds["err"][~sf]).max() < 10                    # misalignments, arcsec; measured: 5.7
    assert np.abs(paper["err"][~sf]).min() > 30                    # measured: 37 to 83 arcsec


def test_without_bias_the_two_variants_agree(unbiased):
    maneuvers, truth = unbiased
    paper, holds = tables(maneuvers, truth)
    sf = paper.index.get_level_values("parameter").str.startswith("sf")
    diff = np.abs(holds["value"] - paper["value"])
    assert diff[sf].max() < 40                                     # ppm; measured: 26
    assert diff[~sf].max() < 8                                     # arcsec; measured: 4.3
    assert np.abs(paper["err"][sf]).max() < 40 and np.abs(holds["err"][sf]).max() < 40  # measured: 13, 27


def test_default_is_the_paper_variant(unbiased):
    data = unbiased[0][0]
    assert classic.classic(data).equals(classic.classic(data, "trusted"))
