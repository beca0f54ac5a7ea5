"""Default priors by the gyro's sensor class, declared once, and the config over them."""

import shutil

import pytest
import yaml

from gyrocal.errors import InputError
from gyrocal.io import telemetry
from gyrocal.model import effects
from gyrocal.model.channels import Channel
from gyrocal.model.sensorclass import SENSOR_CLASSES
from gyrocal.model.spec import ModelSpec

CHANNELS = (Channel("gx", None, "roll"), Channel("gy", None, "pitch"), Channel("gz", None, "yaw"))
MODEL = list(effects.BASELINE) + ["bias_drift", "st_latency"]


def spec():
    return ModelSpec.build("drift", effects.resolve("drift", MODEL, {}), CHANNELS)


@pytest.mark.parametrize("name", ["mems", "fog", "rlg"])
def test_a_class_sets_the_prior_sd_and_bound_it_names_and_no_other(name):
    declared, scaled = spec(), spec().with_sensor_class(name)
    table = SENSOR_CLASSES[name]
    for before, after in zip(declared.parameters, scaled.parameters):
        if (after.effect, after.name) in table:
            assert (after.prior_sd, after.bound) == table[(after.effect, after.name)]
        else:
            assert after == before
    assert scaled.parameters[0].label == "gx.sf_pos"


def test_mems_priors_are_wider_than_a_dtgs():
    dtg, mems = spec(), spec().with_sensor_class("mems")
    sd = {p.label: p.prior_sd for p in mems.parameters}
    assert sd["gx.sf_pos"] == 10000.0 and sd["gy.mis_roll"] == 2000.0 and sd["gz.bias_drift"] == 10.0
    assert all(m.prior_sd >= d.prior_sd for d, m in zip(dtg.parameters, mems.parameters))


def test_no_class_and_dtg_keep_the_declarations_to_the_byte():
    assert spec().with_sensor_class(None).to_json() == spec().to_json() == spec().with_sensor_class("dtg").to_json()


def test_the_config_overrides_the_class():
    mems = spec().with_sensor_class("mems").with_priors({"sf_sd_ppm": 3000.0, "sd": {"bias_drift.bias_drift": 4.0,
                                                                                    "g_sensitivity.g_x": 1.0}})
    sd = {p.label: p.prior_sd for p in mems.parameters}
    assert sd["gx.sf_neg"] == 3000.0 and sd["gz.bias_drift"] == 4.0 and sd["gx.mis_yaw"] == 2000.0


def test_a_prior_sd_for_a_parameter_the_effect_lacks_is_refused():
    with pytest.raises(ValueError, match="bias_drift has no parameter 'drift'"):
        spec().with_priors({"sd": {"bias_drift.drift": 4.0}})


def test_an_unknown_class_is_refused():
    with pytest.raises(ValueError, match="unknown sensor class 'tuning_fork'"):
        spec().with_sensor_class("tuning_fork")


def with_gyro(tiny, tmp_path, gyro):
    campaign_dir = tmp_path / "campaign"
    shutil.copytree(tiny[0], campaign_dir)
    meta = yaml.safe_load((campaign_dir / "campaign.yaml").read_text())
    meta["gyro"] = {**(meta.get("gyro") or {}), **gyro}
    (campaign_dir / "campaign.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    return campaign_dir


def test_campaign_yaml_declares_the_sensor_class(tiny, tmp_path):
    campaign = telemetry.read_campaign(with_gyro(tiny, tmp_path, {"sensor_class": "mems"}))
    assert campaign.gyro["sensor_class"] == "mems"


def test_an_unknown_sensor_class_in_campaign_yaml_is_refused(tiny, tmp_path):
    with pytest.raises(InputError, match="sensor_class"):
        telemetry.read_campaign(with_gyro(tiny, tmp_path, {"sensor_class": "hrg"}))


def test_a_scenarios_sensor_class_reaches_the_campaign_and_the_plan(tmp_path):
    from gyrocal.planning import plan
    from gyrocal.simulation import simulate

    from conftest import DATA, ROOT
    scenario = simulate.load_scenario(DATA / "tiny.yaml")
    scenario["gyro"]["sensor_class"] = "mems"
    campaign, _ = simulate.simulate(scenario)
    telemetry.write_campaign(campaign, tmp_path / "campaign")
    assert telemetry.read_campaign(tmp_path / "campaign").gyro["sensor_class"] == "mems"
    predicted = plan.plan(scenario, plan.read_config(ROOT / "config" / "config.yaml")).table()
    sd = predicted.set_index(["channel", "parameter"])["prior_sd"]
    assert sd[("dtg1_roll", "sf_pos")] == 10000.0 and sd[("dtg1_roll", "mis_yaw")] == 2000.0


def test_each_class_declares_its_limits_and_bounds_its_priors_by_them():
    """The DTG's limits are the effects' declarations (what the checks used before classes had
    limits); every other class bounds its scale-factor and misalignment priors by its own."""
    from gyrocal.checks.sensing import physical_limits
    from gyrocal.model.sensorclass import CLASSES, limits
    from gyrocal.model.units import arcsec_to_rad

    assert (limits(None).sf_bound_ppm, limits("dtg").mis_bound_arcsec) == (effects.SF_BOUND_PPM, 3600.0)
    for name, c in CLASSES.items():
        assert c.arw_deg_sqrt_h[0] < c.arw_deg_sqrt_h[1] and c.bias_bound_deg_h > 0 and c.max_rate_deg_s > 0
        sf, mis, _ = physical_limits(CHANNELS, name)
        assert sf == pytest.approx(c.sf_bound_ppm * 1e-6) and mis == pytest.approx(arcsec_to_rad(c.mis_bound_arcsec))
        for (effect, _), (_, bound) in SENSOR_CLASSES[name].items():
            if effect == "scale_factor":
                assert bound == c.sf_bound_ppm
    assert physical_limits(CHANNELS) == physical_limits(CHANNELS, "dtg")
    assert [CLASSES[n].sf_bound_ppm for n in ("rlg", "fog", "dtg", "mems")] == [5000.0, 10000.0, 30000.0, 50000.0]


def scaled(tiny, tmp_path, error, sensor_class):
    """The tiny campaign with every gyro reading ``1 + error`` times too large (a scale error of
    ``error`` on every channel, both directions), declared of ``sensor_class``."""
    import pandas as pd

    campaign_dir = with_gyro(tiny, tmp_path / sensor_class, {"sensor_class": sensor_class})
    gyro = pd.read_csv(campaign_dir / "gyro.csv")
    channels = [c for c in gyro.columns if c != "time"]
    gyro[channels] *= 1.0 + error
    gyro.to_csv(campaign_dir / "gyro.csv", index=False, float_format="%.17g")
    return campaign_dir


@pytest.mark.parametrize("error, sensor_class, refused", [
    (0.02, "mems", False), (0.02, "fog", True), (0.02, "rlg", True),
    (0.04, "mems", False), (0.04, "dtg", True),
])
def test_the_physics_check_takes_the_scale_bound_of_the_declared_class(tiny, tmp_path, error, sensor_class, refused):
    """A MEMS campaign with a 2 % or 4 % scale error passes the physics check with no config (its
    bound is 5 %); a FOG or RLG one at 2 % (bounds 1 % and 0.5 %) and a DTG one at 4 % (3 %) are
    refused, the check naming the class's bound."""
    from gyrocal import checks
    from gyrocal.model.sensorclass import limits

    directory = scaled(tiny, tmp_path, error, sensor_class)
    if not refused:
        checks.read_checked(directory)
        return
    bound = limits(sensor_class).sf_bound_ppm * 1e-6
    with pytest.raises(InputError, match=rf"physical: \w+ 1 \+/- {bound:.2g}"):
        checks.read_checked(directory)
