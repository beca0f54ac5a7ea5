"""The symmetric scale-factor model: one ``sf`` per channel for both directions of rate."""

import numpy as np
import pytest

from gyrocal.inference import errormodel
from gyrocal.inference.fit import identification
from gyrocal.maneuvers.preprocess import ManeuverData
from gyrocal.model import channels as ch
from gyrocal.model import correction, effects
from gyrocal.model.spec import ModelSpec, baseline
from gyrocal.model.units import PPM

SYMMETRIC = ["scale_factor_symmetric", "misalignment", "bias"]


def symmetric_spec(channels=ch.MOM_CHANNELS):
    return ModelSpec.build("symmetric", effects.resolve("symmetric", SYMMETRIC, {}), channels)


def test_one_sf_per_channel_with_the_prior_of_the_per_direction_ones():
    spec, base = symmetric_spec(), baseline(ch.MOM_CHANNELS)
    assert spec.n_core == 18 and spec.labels[:3] == ["dtg1_roll.sf", "dtg1_roll.mis_pitch", "dtg1_roll.mis_yaw"]
    sf, sf_pos = spec.parameters[0], base.parameters[0]
    assert (sf.unit, sf.prior_sd, sf.bound, sf.si_per_unit) == (sf_pos.unit, sf_pos.prior_sd, sf_pos.bound,
                                                                sf_pos.si_per_unit)
    assert spec.with_priors({"sf_sd_ppm": 300.0}).parameters[0].prior_sd == 300.0


def test_a_model_takes_one_kind_of_scale_factor():
    with pytest.raises(ValueError, match="not both"):
        effects.resolve("m", ["scale_factor", "scale_factor_symmetric", "misalignment", "bias"], {})
    with pytest.raises(ValueError, match=r"add \['scale_factor'\]"):
        effects.resolve("m", ["misalignment", "bias"], {})


def test_sf_sets_both_branches_and_the_correction_is_the_same_both_ways():
    spec = symmetric_spec()
    theta = np.zeros(len(spec))
    theta[spec.index("dtg2_yaw.sf")] = -1712 * PPM
    params = spec.channel_params(theta)
    assert params.sf_pos[2] == params.sf_neg[2] == -1712 * PPM and params.get(2, "sf") == -1712 * PPM
    assert spec.contract(params)["dtg2_yaw"] == pytest.approx({"sf": -1712, "mis_roll": 0, "mis_pitch": 0})
    entry = correction.correction_for_set(params, ("dtg1_roll", "dtg1_pitch", "dtg2_yaw"))
    assert entry["scale_correction_pos"] == entry["scale_correction_neg"]
    assert entry["scale_correction_pos"][2] == pytest.approx(1 / (1 - 1712e-6), rel=1e-12)


def test_the_column_of_sf_is_the_sum_of_the_branch_columns(tiny_run):
    _, npz = tiny_run
    data = ManeuverData.load(npz[0])
    sym, base = symmetric_spec(data.channels), baseline(data.channels)
    theta_sym = np.zeros(len(sym))
    theta_sym[sym.index("dtg1_roll.sf")] = 300 * PPM
    theta_base = base.core_vector(sym.channel_params(theta_sym))
    biases = np.zeros(len(data.channels))
    a = errormodel.linearize(data, sym, theta_sym, biases).design
    b = errormodel.linearize(data, base, theta_base, biases).design
    for c in data.channels:
        both = b[..., base.index(f"{c.name}.sf_pos")] + b[..., base.index(f"{c.name}.sf_neg")]
        assert np.allclose(a[..., sym.index(f"{c.name}.sf")], both, rtol=1e-12, atol=1e-18)


def test_a_symmetric_sf_needs_a_maneuver_about_its_axis_in_either_direction(tiny_run):
    _, npz = tiny_run
    maneuvers = [ManeuverData.load(p) for p in npz]
    spec = symmetric_spec(maneuvers[0].channels)
    about_roll = [d for d in maneuvers if d.axis != "roll"]
    reasons = identification.unflown(about_roll, spec)
    assert {k: v for k, v in reasons.items() if k.endswith(".sf")} == {
        f"{c.name}.sf": "no roll turn in the data: turn about roll, either way" for c in spec.channels if c.axis == "roll"}
    assert not {k for k in identification.unflown(maneuvers, spec) if k.endswith(".sf")}
