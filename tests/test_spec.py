"""The model specification: one declaration of every parameter, and what derives from it."""

import json

import numpy as np
import pandas as pd
import pytest

from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.model import channels as ch
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec, baseline
from gyrocal.model.units import ARCSEC_RAD, PPM

from conftest import DATA, config_with, run_campaign

BASE = ["scale_factor", "misalignment", "bias"]


def spec_of(names, plugins=None):
    return ModelSpec.build("m", effects.resolve("m", names, plugins or {}), ch.MOM_CHANNELS)


def test_baseline_has_four_terms_per_channel_channel_by_channel_in_the_declared_units():
    spec = baseline(ch.MOM_CHANNELS)
    assert len(spec) == spec.n_core == 24
    assert spec.labels[:8] == ["dtg1_roll.sf_pos", "dtg1_roll.sf_neg", "dtg1_roll.mis_pitch", "dtg1_roll.mis_yaw",
                               "dtg1_pitch.sf_pos", "dtg1_pitch.sf_neg", "dtg1_pitch.mis_roll", "dtg1_pitch.mis_yaw"]
    assert spec.units[:4] == ["ppm", "ppm", "arcsec", "arcsec"]
    assert spec.si_per_unit[:4] == pytest.approx([PPM, PPM, ARCSEC_RAD, ARCSEC_RAD], rel=1e-15)
    assert spec.prior_sd_si[:4] == pytest.approx([5000 * PPM, 5000 * PPM, 1000 * ARCSEC_RAD, 1000 * ARCSEC_RAD])
    assert spec.bound_si[:4] == pytest.approx([30000 * PPM, 30000 * PPM, 3600 * ARCSEC_RAD, 3600 * ARCSEC_RAD])


def test_extra_effects_follow_the_channel_terms_per_channel_or_per_campaign():
    spec = spec_of(BASE + ["bias_drift", "st_latency"])
    assert spec.n_core == 24 and len(spec) == 31
    assert spec.labels[24] == "dtg1_roll.bias_drift" and spec.parameters[24].channel == 0
    assert spec.labels[30] == "st_latency.latency" and spec.parameters[30].channel is None
    assert spec.parameters[30].owner == "st_latency" and spec.units[30] == "ms" and spec.si_per_unit[30] == 1e-3


def test_vector_channel_model_and_contract_round_trip():
    spec = spec_of(BASE + ["bias_drift"])
    theta = np.random.default_rng(0).normal(0, 1e-3, len(spec))
    params = spec.channel_params(theta, np.arange(6) * 1e-7)
    assert np.array_equal(spec.core_vector(params), theta[:24])
    assert params.mis_rad[0, 1] == theta[2] and params.mis_rad[0, 0] == 0.0
    assert np.array_equal(params.bias_rad_s, np.arange(6) * 1e-7)
    back = spec.params_from_contract(spec.contract(params))
    assert np.allclose(spec.core_vector(back), theta[:24], rtol=1e-14, atol=0)
    assert np.allclose(spec.to_si(spec.to_unit(theta)), theta, rtol=1e-15, atol=0)


def test_specification_survives_its_file_with_or_without_the_effect_objects():
    spec = spec_of(BASE + ["st_latency", "st_correlated_noise"])
    again = ModelSpec.from_json(spec.to_json(), effects.LIBRARY)
    assert again.parameters == spec.parameters and again.correlated_noise
    assert again.effect("st_latency") is effects.LIBRARY["st_latency"]
    declarations_only = ModelSpec.from_json(spec.to_json())
    assert declarations_only.labels == spec.labels
    with pytest.raises(ValueError, match="effect st_latency is not loaded"):
        declarations_only.effect("st_latency")
    with pytest.raises(ValueError, match=r"uses effect\(s\) \['st_latency'"):
        ModelSpec.from_json(spec.to_json(), {k: v for k, v in effects.LIBRARY.items() if k != "st_latency"})
    assert "Infinity" not in spec.to_json() and json.loads(spec.to_json())["parameters"][0]["bound"] == 30000.0


def test_config_overrides_a_declared_prior_and_refuses_a_unit_it_does_not_declare():
    spec = spec_of(BASE).with_priors({"sf_sd_ppm": 100.0, "mis_bound_arcsec": 60.0, "noise_log_sd": 1.0})
    assert spec.prior_sd_si[:4] == pytest.approx([100 * PPM, 100 * PPM, 1000 * ARCSEC_RAD, 1000 * ARCSEC_RAD])
    assert spec.bound_si[:4] == pytest.approx([30000 * PPM, 30000 * PPM, 60 * ARCSEC_RAD, 60 * ARCSEC_RAD])
    earlier = pd.DataFrame([{"channel": "dtg2_yaw", "parameter": "sf_pos", "unit": "arcsec", "mean": 1.0, "sd": 1.0}])
    with pytest.raises(ValueError, match=r"earlier\.csv: dtg2_yaw\.sf_pos is in arcsec, but this model declares it in ppm"):
        spec_of(BASE).with_priors({}, earlier, "earlier.csv")


def test_a_plugin_parameter_in_arcsec_is_not_taken_for_a_channel_term(tmp_path):
    plugins = effects.load_plugins([DATA / "plugin_cyclic_error.py"])
    spec = spec_of(BASE + ["cyclic_error"], plugins)
    assert spec.n_core == 24 and spec.labels[24:] == ["cyclic_error.amplitude"]
    assert spec.units[24:] == ["arcsec"] and not any(p.core for p in spec.extras)


def test_a_model_with_an_arcsec_plugin_parameter_runs_end_to_end(tiny, tmp_path, config):
    """Every step, through the report, with one campaign-wide arcsec row after the 24."""
    plugin = str(DATA / "plugin_cyclic_error.py")
    cfg = config_with(config, {"cyclic": BASE + ["cyclic_error"]}, [plugin])
    run_campaign(tiny[0], tmp_path, cfg, ("cyclic",), tiny[0].parent / "truth.json")
    table = pd.read_csv(tmp_path / "cyclic" / "calibration.csv")
    assert len(table) == 25 + 12   # and the derived sf_mean, sf_asym per channel after them
    extra = table.iloc[24]
    assert (extra["channel"], extra["parameter"], extra["unit"]) == ("cyclic_error", "amplitude", "arcsec")
    assert extra["ci95_low"] < 0 < extra["ci95_high"]           # the simulation has no cyclic error
    assert extra["ci95_high"] - extra["ci95_low"] < 30           # and the data say so, well inside the prior
    assert PointEstimate.load(tmp_path / "cyclic" / "point_estimate.npz").spec.n_core == 24
    html = (tmp_path / "report.html").read_text()
    assert "model reviewed: <b>cyclic</b>" in html and "cyclic_error" in html
    assert "class='verdict go'>GO<" in html


def test_start_points_with_zero_density_are_redrawn_a_bounded_number_of_times_then_refused():
    from gyrocal.inference.sampling.ensemble import START_REDRAWS, run_ensembles
    from gyrocal.inference.sampling.proposal import SamplingError
    calls = []

    def nowhere(x):
        calls.append(len(x))
        return np.full(len(x), -np.inf)

    cfg = {"walkers": 8, "ensembles": 1, "burn_steps": 10, "chunk_steps": 10, "min_tau_multiple": 1,
           "max_steps": 20, "initial_steps": 10}
    with pytest.raises(SamplingError, match=r"after 100 redraws, 8 of 8 start points of ensemble 0 still have zero"):
        run_ensembles(nowhere, np.zeros(3), np.eye(3), cfg, seed=1)
    assert len(calls) == START_REDRAWS + 1
