"""Scenario files (``config/scenarios/*.yaml``): their keys, defaults and ``base:`` inheritance.

What a simulation or a plan flies, read without the simulator: the workflow reads a scenario's
campaign name and maneuver ids when it builds its DAG, before any job runs, so this module
imports only numpy, yaml and jsonschema (the simulator's scipy.signal alone takes 0.7 s). Each
file is read by `gyrocal.io.yamlfile` and checked against
``gyrocal/io/schemas/scenario.schema.json`` on its own, before ``base:`` merges it; a refusal is
a `TelemetryError` naming the file, the key and its line.
"""

import copy
from pathlib import Path

from gyrocal.io.yamlfile import TelemetryError, check_schema, read_yaml
from gyrocal.model import channels as ch

__all__ = ["DEFAULTS", "EFFECT_DEFAULTS", "STAR_TRACKER_GM", "load_scenario", "peek"]

DEFAULTS = {
    "name": "simulated",
    "seed": 0,
    "gyro_hz": 10.0,
    "star_tracker_hz": 1.0,
    "truth_substeps": 4,
    "t0_s": 1000.0,
    "channels": {c.name: {"dtg": c.dtg, "axis": c.axis} for c in ch.MOM_CHANNELS},
    "in_loop": ["dtg1_roll", "dtg2_pitch", "dtg2_yaw"],
    "truth": {},
    "gyro": {"arw_deg_sqrt_h": 0.003, "pulse_arcsec": 0.05, "bias_sd_deg_h": 0.01},
    "star_tracker": {"sigma_cross_arcsec": 10.0, "sigma_about_arcsec": 40.0,
                     "boresight_body": [0.0, 0.0, 1.0], "invalid_fraction": 0.0,
                     "gm_sigma_cross_arcsec": 0.0, "gm_sigma_about_arcsec": 0.0, "gm_tau_s": 0.0,
                     "gm_clock_s_per_rad": 0.0},
    "maneuver_defaults": {"angle_deg": 90.0, "rate_deg_s": 0.15, "accel_deg_s2": 0.005,
                          "hold_s": 400.0, "gap_s": 120.0, "uncontrolled_rate_deg_s": 3e-4},
    "maneuvers": [],
    "effects": {},
    "accelerometer": {"gravity_m_s2": 0.0, "noise_m_s2": 0.002},
}

STAR_TRACKER_GM = ("gm_sigma_cross_arcsec", "gm_sigma_about_arcsec", "gm_tau_s")
"""The star tracker's first-order Gauss-Markov part, added to its white noise: its stationary sd
across and about the boresight and its correlation time (off while a sigma or tau is 0)."""

EFFECT_DEFAULTS = {
    "bias_drift_deg_h_per_h": 0.0,
    "sf_nonlinearity_ppm_per_deg2_s2": 0.0,
    "st_latency_s": 0.0,
    "st_correlation_time_s": 0.0,
    "st_jitter_ms": 0.0,
    "sf_temperature_ppm_per_K": 0.0,
    "temperature_swing_K": 0.0,
    "g_sensitivity_deg_s_per_g": 0.0,
    "gravity_offset_arcsec_per_g": 0.0,
}
"""Optional hidden effects, all off by default; magnitudes in the units of their names. The two
per g need ``accelerometer.gravity_m_s2`` (a campaign on a rate table in a lab): every channel's
bias then follows ``g_sensitivity`` times the specific force along each body axis, and the star
tracker sits ``gravity_offset`` per g of the force along each of the two other axes off about each
body axis, as the library effects of those names describe them with every coefficient equal.
``st_jitter_ms``: each star-tracker attitude is the truth at its time tag plus a white normal error
of this sd (the reference's clock jittering against the gyros'; the library's ``st_jitter``)."""


def _merge(defaults: dict, given: dict, where: str) -> dict:
    unknown = set(given) - set(defaults)
    if unknown:
        raise TelemetryError(f"{where}: unknown key(s) {sorted(unknown)}; allowed: {sorted(defaults)}")
    out = copy.deepcopy(defaults)
    for key, value in given.items():
        if isinstance(defaults[key], dict) and key not in ("channels", "truth", "effects"):
            out[key] = _merge(defaults[key], value or {}, f"{where}.{key}")
        else:
            out[key] = value
    return out


def _read_given(path: Path, seen=()) -> dict:
    """A scenario file's keys; with ``base: OTHER.yaml`` (beside it), the other file's keys with
    this one's in their place, section by section."""
    document = read_yaml(path)
    check_schema(document, "scenario")
    given = document.data or {}
    if "base" not in given:
        return given
    target = path.parent / given.pop("base")
    where = f"base (line {document.line(['base'])})"
    if target.resolve() in seen or target.resolve() == path.resolve():
        raise TelemetryError.at(path, f"{target} is a base of itself (a loop of base: files)", where)
    if not target.is_file():
        raise TelemetryError.at(path, f"the base scenario {target} is not a file", where,
                                "base: is a path relative to this file's folder")
    base = _read_given(target, (*seen, path.resolve()))
    for key, value in given.items():
        both_dicts = isinstance(value, dict) and isinstance(base.get(key), dict)
        base[key] = {**base[key], **value} if both_dicts and key not in ("truth", "channels") else value
    return base


def load_scenario(path) -> dict:
    """Read a scenario YAML and fill in defaults; an unknown key is an error."""
    path = Path(path)
    given = _read_given(path)
    scenario = _merge(DEFAULTS, given, str(path))
    scenario["effects"] = _merge(EFFECT_DEFAULTS, scenario["effects"], f"{path}: effects")
    if not scenario["maneuvers"]:
        raise TelemetryError.at(path, "the scenario has no maneuvers", todo="list them under maneuvers:")
    eff = scenario["effects"]
    if (eff["g_sensitivity_deg_s_per_g"] or eff["gravity_offset_arcsec_per_g"]) and not \
            scenario["accelerometer"]["gravity_m_s2"]:
        raise TelemetryError(f"{path}: an effect per g needs accelerometer.gravity_m_s2 (a campaign in a lab); "
                             "in orbit the accelerometers read no gravity")
    return scenario


def peek(scenario_path) -> dict:
    """The campaign name and maneuver ids a scenario will produce (for the workflow's DAG)."""
    scenario = load_scenario(scenario_path)
    return {"name": scenario["name"], "maneuvers": [m["id"] for m in scenario["maneuvers"]]}
