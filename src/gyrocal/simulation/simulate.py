"""A Mars-Orbiter-like spacecraft: three two-axis DTGs, a star tracker, single-axis maneuvers,
eigen-axis slews (about a unit vector in body axes) and tumbles (a body rate vector, constant or
slowly varying); the last two are free motion in the campaign it writes (no axis label).

Every setting comes from a scenario YAML (``config/scenarios/*.yaml``). The true body
rate is piecewise constant on a fine grid, so the true attitude is propagated exactly;
the gyros integrate that rate through the channel model (docs/interface.md section 2) plus
angle random walk and pulse quantisation, and the star tracker samples the true
attitude with anisotropic white noise, plus, where the scenario declares one, a first-order
Gauss-Markov part of its own sd and correlation time. A maneuver's ``noise_scale`` multiplies
the white noise and the angle random walk inside its window.
"""

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from gyrocal.io.campaign_yaml import DEFAULT_NOISE_GROUP
from gyrocal.io.outputs import write_text
from gyrocal.io.scenario import load_scenario
from gyrocal.io.telemetry import Campaign, Maneuver, write_campaign
from gyrocal.model import channels as ch
from gyrocal.model import kinematics
from gyrocal.model.spec import ModelSpec, baseline
from gyrocal.model.units import (
    AXIS_INDEX,
    PPM,
    STANDARD_GRAVITY_M_S2,
    arcsec_to_rad,
    arw_to_rad_sqrt_s,
    deg_h_to_rad_s,
    rad_s_to_deg_h,
)

__all__ = [
    "STATED_ARW_FLOOR_DEG_SQRT_H",
    "ManeuverProfile",
    "build_profiles",
    "gauss_markov",
    "maneuver_scale",
    "run",
    "scatter_truth",
    "scenario_channels",
    "simulate",
    "star_tracker_noise",
    "stated_star_tracker",
    "truth_parameters",
]


@dataclass
class ManeuverProfile:
    """Timing of one maneuver: hold, ramp up, coast, ramp down, hold, about ``vector`` (body axes;
    a single-axis maneuver's is its axis), plus a tumble's slow ``wobble``."""

    id: str
    axis: str | None
    """The labelled axis; None for free motion (an eigen-axis slew, a tumble)."""
    sign: float
    t_start: float
    rate_rad_s: float
    accel_rad_s2: float
    hold_s: float
    coast_s: float
    noise_scale: float = 1.0
    noise_group: str = DEFAULT_NOISE_GROUP
    vector: tuple = None
    """Unit vector of the rotation in body axes (None: the labelled axis)."""
    wobble_rad_s: tuple = (0.0, 0.0, 0.0)
    """A tumble's slowly varying part: a body rate vector times ``sin(2 pi t / wobble_period_s)``, with the ramps."""
    wobble_period_s: float = 600.0

    @property
    def ramp_s(self):
        return self.rate_rad_s / self.accel_rad_s2

    @property
    def t_end(self):
        return self.t_start + 2 * self.hold_s + 2 * self.ramp_s + self.coast_s

    def rate(self, t):
        """Commanded rate about the maneuver axis at times ``t`` (rad/s)."""
        tau = np.asarray(t) - self.t_start - self.hold_s
        r, c = self.ramp_s, self.coast_s
        up = np.clip(tau / r, 0.0, 1.0)
        down = np.clip((tau - r - c) / r, 0.0, 1.0)
        return self.sign * self.rate_rad_s * (up - down)

    def body_rate(self, t) -> np.ndarray:
        """(n, 3) commanded body rate at times ``t`` (rad/s)."""
        vector = np.eye(3)[AXIS_INDEX[self.axis]] if self.vector is None else np.asarray(self.vector, dtype=float)
        rate = self.rate(t)[:, None] * vector
        if any(self.wobble_rad_s):
            tau = np.asarray(t) - self.t_start - self.hold_s
            envelope = np.abs(self.rate(t)) / self.rate_rad_s
            rate = rate + (envelope * np.sin(2 * np.pi * tau / self.wobble_period_s))[:, None] * np.asarray(
                self.wobble_rad_s)
        return rate


def build_profiles(scenario) -> list:
    """The maneuvers' profiles, one after the other: a single-axis slew (``axis: yaw``, ``direction``),
    an eigen-axis slew (``axis: [x, y, z]``, a unit vector in body axes, its ``angle_deg`` about it) or
    a tumble (``rate_deg_s: [x, y, z]``, the body rate for ``duration_s`` between its ramps, with an
    optional ``wobble_deg_s`` of period ``wobble_period_s``)."""
    d = scenario["maneuver_defaults"]
    t = scenario["t0_s"] + d["gap_s"]
    profiles = []
    for entry in scenario["maneuvers"]:
        m = {**d, **entry}
        accel = np.deg2rad(m["accel_deg_s2"])
        sign = -1.0 if m.get("direction") == "-" else 1.0
        wobble = tuple(np.deg2rad(m.get("wobble_deg_s") or [0.0, 0.0, 0.0]))
        if isinstance(m["rate_deg_s"], list):  # a tumble
            rate_vector = np.deg2rad(np.asarray(m["rate_deg_s"], dtype=float))
            rate = float(np.linalg.norm(rate_vector))
            if rate == 0 or "duration_s" not in m:
                raise ValueError(f"maneuver {m['id']}: a tumble needs a non-zero rate_deg_s vector and its duration_s")
            axis, vector, coast = None, tuple(rate_vector / rate), float(m["duration_s"])
        else:
            rate = np.deg2rad(m["rate_deg_s"])
            coast = np.deg2rad(m["angle_deg"]) / rate - rate / accel
            if coast < 0:
                raise ValueError(f"maneuver {m['id']}: angle too small to reach the rate; lower rate_deg_s")
            if isinstance(m["axis"], list):  # an eigen-axis slew
                v = np.asarray(m["axis"], dtype=float)
                if abs(np.linalg.norm(v) - 1.0) > 1e-3:
                    raise ValueError(f"maneuver {m['id']}: axis {m['axis']} is not a unit vector in body axes")
                axis, vector = None, tuple(v / np.linalg.norm(v))
            else:
                axis, vector = m["axis"], None
        p = ManeuverProfile(m["id"], axis, sign, t, rate, accel, m["hold_s"], coast, float(m.get("noise_scale", 1.0)),
                            m.get("noise_group", DEFAULT_NOISE_GROUP), vector, wobble,
                            float(m.get("wobble_period_s", 600.0)))
        profiles.append(p)
        t = p.t_end + m["gap_s"]
    return profiles


def _uncontrolled_rates(amplitude_rad_s, rng):
    """Small limit-cycle rates on every axis: a few slow sinusoids with random phases.

    Draws them now and returns the rates as a function of time, to be evaluated block by block.
    """
    periods = rng.uniform(60.0, 400.0, size=(3, 3))
    phases = rng.uniform(0, 2 * np.pi, size=(3, 3))
    weights = rng.uniform(0.3, 1.0, size=(3, 3))
    weights /= weights.sum(axis=1, keepdims=True)

    def rates(t):
        arg = 2 * np.pi * t[:, None, None] / periods[None] + phases[None]
        return amplitude_rad_s * np.sum(weights[None] * np.sin(arg), axis=2)
    return rates


def _temperatures(t_first, t_last, dtgs, swing_K, rng):
    """Slow DTG temperature excursions (K about a 0 reference) over ``[t_first, t_last]``, one
    series per DTG: drawn now, returned as a function of time (None without a swing)."""
    if swing_K == 0:
        return None
    span = t_last - t_first
    waves = {}
    for dtg in dtgs:
        period = span * rng.uniform(0.6, 1.2)
        phase = rng.uniform(0, 2 * np.pi)
        waves[f"temp_dtg{dtg}"] = (period, phase)

    def temperatures(t):
        return {name: swing_K * np.sin(2 * np.pi * (t - t_first) / period + phase)
                for name, (period, phase) in waves.items()}
    return temperatures


STATED_ARW_FLOOR_DEG_SQRT_H = 1e-6
"""The ARW ``campaign.yaml`` states for gyros simulated without noise: a stated noise must be positive
(the fit weighs by it), and this is a hundred times below the best navigation-grade gyros' 1e-4
deg/sqrt(h); the data themselves are simulated without any walk."""

GYRO_BLOCK = 1 << 15
"""Gyro samples per block of the fine truth grid: each block's arrays are a few MB, so the
simulator holds the fine grid's increments and attitudes and little else, however long the
campaign (a block's rows give the same numbers as the whole grid's)."""


def truth_parameters(spec: ModelSpec, truth: ch.ChannelParams) -> dict:
    """``truth.json``'s parameters: the channel model in the contract's units and each bias in deg/h."""
    out = spec.contract(truth)
    for i, c in enumerate(spec.channels):
        out[c.name]["bias_deg_h"] = rad_s_to_deg_h(truth.bias_rad_s[i])
    return {c: {k: round(float(v), 9) for k, v in entry.items()} for c, entry in out.items()}


def scenario_channels(scenario: dict) -> tuple:
    """The gyro channels a scenario flies."""
    return tuple(ch.Channel(n, int(v["dtg"]), v["axis"]) for n, v in scenario["channels"].items())


def simulate(scenario: dict, seed=None):
    """Simulate a campaign; returns ``(Campaign, truth_dict)``."""
    seed = scenario["seed"] if seed is None else seed
    rng = np.random.default_rng(seed)
    channels = scenario_channels(scenario)
    spec = baseline(channels)
    truth = spec.params_from_contract(scenario["truth"])
    gyro_cfg, st_cfg, eff = scenario["gyro"], scenario["star_tracker"], scenario["effects"]
    given_bias = [scenario["truth"].get(c.name, {}).get("bias_deg_h") for c in channels]
    truth.bias_rad_s[:] = deg_h_to_rad_s([0.0 if b is None else b for b in given_bias])
    idx = [i for i, b in enumerate(given_bias) if b is None]
    if idx:
        truth.bias_rad_s[idx] = deg_h_to_rad_s(rng.normal(0, gyro_cfg["bias_sd_deg_h"], len(idx)))

    profiles = build_profiles(scenario)
    dt_g = 1.0 / scenario["gyro_hz"]
    n_sub = int(scenario["truth_substeps"])
    t0 = scenario["t0_s"]
    t_final = profiles[-1].t_end + scenario["maneuver_defaults"]["gap_s"]
    n_gyro = int(np.ceil((t_final - t0) / dt_g))
    dt_sub = dt_g / n_sub
    blocks = [(g, min(g + GYRO_BLOCK, n_gyro)) for g in range(0, n_gyro, GYRO_BLOCK)]

    def t_mid(g, h):
        """Midpoints of the fine steps of gyro samples ``g:h``."""
        t_fine = t0 + dt_sub * np.arange(g * n_sub, h * n_sub + 1)
        return 0.5 * (t_fine[1:] + t_fine[:-1])

    uncontrolled = _uncontrolled_rates(np.deg2rad(scenario["maneuver_defaults"]["uncontrolled_rate_deg_s"]), rng)

    def true_rate(t):
        rate = uncontrolled(t)
        for p in profiles:
            rate += p.body_rate(t)
        return rate

    increments_fine = np.empty((n_gyro * n_sub, 3))
    for g, h in blocks:
        increments_fine[g * n_sub:h * n_sub] = true_rate(t_mid(g, h)) * dt_sub
    attitude0 = Rotation.random(random_state=rng.integers(2**32))
    attitudes_fine = kinematics.propagate(attitude0, increments_fine)

    # Gyro channels: model of docs/interface.md section 2 with the optional effects, block by block.
    temperatures = _temperatures(t_mid(0, 1)[0], t_mid(n_gyro - 1, n_gyro)[-1], sorted({c.dtg for c in channels}),
                                 eff["temperature_swing_K"], rng)
    drift = deg_h_to_rad_s(eff["bias_drift_deg_h_per_h"]) / 3600.0  # rad/s per s
    gravity = scenario["accelerometer"]["gravity_m_s2"]
    g_rad_s = np.deg2rad(eff["g_sensitivity_deg_s_per_g"]) / STANDARD_GRAVITY_M_S2
    continuous = np.empty((n_gyro, len(channels)))
    temp_means = {f"temp_dtg{dtg}": np.empty(n_gyro) for dtg in sorted({c.dtg for c in channels})} if temperatures else {}
    force = np.empty((n_gyro, 3)) if gravity else None
    for g, h in blocks:
        rows = slice(g * n_sub, h * n_sub)
        t = t_mid(g, h)
        increments = increments_fine[rows]
        extra_scale = np.zeros((len(t), len(channels)))
        if eff["sf_nonlinearity_ppm_per_deg2_s2"]:
            own = np.rad2deg(true_rate(t)[:, ch.input_axes(channels)])
            extra_scale += eff["sf_nonlinearity_ppm_per_deg2_s2"] * PPM * own**2
        temps = temperatures(t) if temperatures else {}
        for i, c in enumerate(channels):
            if temps:
                extra_scale[:, i] += eff["sf_temperature_ppm_per_K"] * PPM * temps[f"temp_dtg{c.dtg}"]
        fine = ch.measure(increments, truth, dt_s=np.full(len(t), dt_sub), extra_scale=extra_scale)
        fine += drift * (t - t0)[:, None] * dt_sub
        if gravity:  # a lab: at rest the accelerometers sense +g along the room's vertical (inertial z)
            mid = kinematics.compose(attitudes_fine[rows], Rotation.from_rotvec(0.5 * increments))
            force_fine = mid.inv().apply([0.0, 0.0, gravity])
            fine += (g_rad_s * force_fine.sum(axis=1) * dt_sub)[:, None]
            force[g:h] = force_fine.reshape(h - g, n_sub, 3).mean(axis=1)
        continuous[g:h] = fine.reshape(h - g, n_sub, len(channels)).sum(axis=1)
        for name, series in temps.items():
            temp_means[name][g:h] = series.reshape(h - g, n_sub).mean(axis=1)
    arw = arw_to_rad_sqrt_s(gyro_cfg["arw_deg_sqrt_h"])
    t_gyro = t0 + dt_g * np.arange(1, n_gyro + 1)
    continuous += rng.normal(0.0, arw * np.sqrt(dt_g), continuous.shape) * maneuver_scale(profiles, t_gyro, True)[:, None]
    pulse = arcsec_to_rad(gyro_cfg["pulse_arcsec"])
    if pulse > 0:
        counts = np.floor(np.cumsum(continuous, axis=0) / pulse)
        gyro_increments = pulse * np.diff(np.vstack([np.zeros(len(channels)), counts]), axis=0)
    else:
        gyro_increments = continuous

    # Star tracker: true attitude at its (possibly late) sample times, times its noise.
    dt_st = 1.0 / scenario["star_tracker_hz"]
    t_st = t0 + eff["st_latency_s"] + dt_st * np.arange(int((t_final - t0 - eff["st_latency_s"]) / dt_st))
    taken = t_st - eff["st_latency_s"]
    if eff["st_jitter_ms"]:  # the attitude of a time off its tag by the clocks' jitter (no draw while off)
        fine_end = t0 + dt_sub * n_gyro * n_sub
        taken = np.clip(taken + rng.normal(0.0, eff["st_jitter_ms"] * 1e-3, len(t_st)), t0, fine_end)
    true_st = kinematics.attitude_at(t0 + dt_sub * np.arange(n_gyro * n_sub + 1), attitudes_fine, increments_fine,
                                     taken)
    del attitudes_fine, increments_fine
    turned = kinematics.net_turns(true_st[0], true_st) if st_cfg.get("gm_clock_s_per_rad") else None
    noise = star_tracker_noise(len(t_st), dt_st, st_cfg, eff["st_correlation_time_s"], rng,
                               maneuver_scale(profiles, t_st, False), turned)
    measured = true_st * Rotation.from_rotvec(noise)
    if eff["gravity_offset_arcsec_per_g"]:
        force_st = true_st.inv().apply([0.0, 0.0, gravity]) / STANDARD_GRAVITY_M_S2
        offset = arcsec_to_rad(eff["gravity_offset_arcsec_per_g"]) * (force_st.sum(axis=1, keepdims=True) - force_st)
        measured = measured * Rotation.from_rotvec(offset)
    quat = measured.as_quat()
    valid = np.ones(len(t_st), dtype=int)
    n_bad = round(st_cfg["invalid_fraction"] * len(t_st))
    if n_bad:
        bad = rng.choice(len(t_st), n_bad, replace=False)
        valid[bad] = 0
        quat[bad] = Rotation.random(n_bad, random_state=rng.integers(2**32)).as_quat()

    gyro_columns = {c.name: gyro_increments[:, i] for i, c in enumerate(channels)}
    for name, mean in temp_means.items():
        gyro_columns[name] = mean + rng.normal(0, 0.01, n_gyro)
    if gravity:  # each interval's mean specific force, as an accelerometer logged beside the gyros
        force += rng.normal(0.0, scenario["accelerometer"]["noise_m_s2"], force.shape)
        for i, a in enumerate("xyz"):
            gyro_columns[f"acc_{a}"] = force[:, i]
    campaign = Campaign(
        name=scenario["name"],
        channels=channels,
        star_tracker=stated_star_tracker(st_cfg),
        gyro={"arw_deg_sqrt_h": max(gyro_cfg["arw_deg_sqrt_h"], STATED_ARW_FLOOR_DEG_SQRT_H),
              **({"sensor_class": gyro_cfg["sensor_class"]} if gyro_cfg.get("sensor_class") else {})},
        maneuvers=tuple(Maneuver(p.id, p.axis, None if p.axis is None else "+" if p.sign > 0 else "-", p.t_start, p.t_end,
                                 tuple(scenario["in_loop"]), p.noise_group) for p in profiles),
        st_time=t_st, st_quat=quat, st_valid=valid,
        gyro_time=t_gyro, gyro_columns=gyro_columns,
    )
    truth_out = {
        "seed": int(seed),
        "parameters": truth_parameters(spec, truth),
        "noise": {"sigma_cross_arcsec": st_cfg["sigma_cross_arcsec"],
                  "sigma_about_arcsec": st_cfg["sigma_about_arcsec"],
                  "arw_deg_sqrt_h": gyro_cfg["arw_deg_sqrt_h"]},
        "effects": {k: v for k, v in eff.items() if v},
    }
    if st_cfg["gm_tau_s"] and (st_cfg["gm_sigma_cross_arcsec"] or st_cfg["gm_sigma_about_arcsec"]):
        truth_out["noise"].update({k: st_cfg[k] for k in ("gm_sigma_cross_arcsec", "gm_sigma_about_arcsec", "gm_tau_s")})
        if st_cfg.get("gm_clock_s_per_rad"):
            truth_out["noise"]["gm_clock_s_per_rad"] = st_cfg["gm_clock_s_per_rad"]
    if any(p.noise_scale != 1.0 or p.noise_group != DEFAULT_NOISE_GROUP for p in profiles):
        truth_out["maneuver_noise"] = {p.id: {"noise_scale": p.noise_scale, "noise_group": p.noise_group}
                                       for p in profiles}
    return campaign, truth_out


def maneuver_scale(profiles, times, closed_start: bool) -> np.ndarray:
    """Each time's noise scale: its maneuver's ``noise_scale`` inside ``[t_start, t_end]`` (a gyro
    interval, ``closed_start`` false, from just after ``t_start``: it ends at its time), else 1."""
    scale = np.ones(len(times))
    for p in profiles:
        if p.noise_scale != 1.0:
            start = (times > p.t_start) if closed_start else (times >= p.t_start)
            scale[start & (times <= p.t_end)] = p.noise_scale
    return scale


def scatter_truth(scenario: dict, rng, sf_sd_ppm: float, mis_sd_arcsec: float) -> None:
    """Replace every channel's truth in ``scenario`` by zero-mean normal draws from ``rng`` (scale
    factors with ``sf_sd_ppm``, misalignments with ``mis_sd_arcsec``), channel by channel and key by key
    in the scenario's order: truths as wide as a prior, untruncated, for accuracy studies."""
    for values in scenario["truth"].values():
        for key in values:
            values[key] = float(rng.normal(0.0, sf_sd_ppm if key.startswith("sf") else mis_sd_arcsec))


def stated_star_tracker(st_cfg: dict) -> dict:
    """The star tracker as ``campaign.yaml`` states it: its total sd across and about the boresight,
    as a data sheet gives it (the white part and the Gauss-Markov part added in quadrature)."""
    gm = st_cfg.get("gm_tau_s", 0.0) > 0
    total = {k: float(np.hypot(st_cfg[k], st_cfg.get(f"gm_{k}", 0.0) if gm else 0.0))
             for k in ("sigma_cross_arcsec", "sigma_about_arcsec")}
    return {**total, "boresight_body": st_cfg["boresight_body"]}


def gauss_markov(white, dt_s, tau_s) -> np.ndarray:
    """Unit-variance first-order Gauss-Markov samples every ``dt_s`` from unit white ``white``
    (rows in time): the exact AR(1) of the continuous process, x[k] = phi x[k-1] +
    sqrt(1 - phi^2) w[k] with phi = exp(-dt/tau), started from its stationary distribution, so
    every sample has variance 1 and lag-k correlation phi^k. ``dt_s`` one step for every sample, or
    one a sample (the first unused): then `gauss_markov_steps`."""
    from scipy.signal import lfilter  # 0.7 s to import, for this case alone

    if np.ndim(dt_s):
        return gauss_markov_steps(white, np.asarray(dt_s, dtype=float) / tau_s)
    phi = np.exp(-dt_s / tau_s)
    white = white.copy()
    white[0] /= np.sqrt(1 - phi**2)
    return lfilter([np.sqrt(1 - phi**2)], [1.0, -phi], white, axis=0)


GM_BLOCK_DECAY = 50.0
"""`gauss_markov_steps` sums the recursion in blocks over which the decay ``sum(step / tau)`` stays
below this, so that ``exp`` of it neither overflows nor loses the carried state."""


def gauss_markov_steps(white, decay) -> np.ndarray:
    """Unit-variance Gauss-Markov samples whose step k decays by ``exp(-decay[k])`` (``decay[0]`` unused:
    the first sample is stationary), from unit white ``white`` (rows in time): x[k] = phi_k x[k-1] +
    sqrt(1 - phi_k^2) w[k], summed in closed form within blocks (`GM_BLOCK_DECAY`), x[k] = e^(-C_k)
    (x[start - 1] + sum_j e^(C_j) sqrt(1 - phi_j^2) w[j]) with C the decay summed from the block's start.
    A clock that runs on the angle turned as well as on time has such steps."""
    decay = np.minimum(np.asarray(decay, dtype=float), GM_BLOCK_DECAY)
    decay[0] = 0.0
    white = np.asarray(white, dtype=float)
    innovation = white.reshape(len(decay), -1) * np.sqrt(-np.expm1(-2.0 * decay))[:, None]
    innovation[0] = white.reshape(len(decay), -1)[0]
    out = np.empty_like(innovation)
    block = np.floor(np.cumsum(decay) / GM_BLOCK_DECAY)
    starts = np.flatnonzero(np.diff(block, prepend=-1.0))
    carried = np.zeros(innovation.shape[1:])
    for start, stop in zip(starts, [*starts[1:], len(decay)]):
        c = np.cumsum(decay[start:stop])[:, None]
        out[start:stop] = np.exp(-c) * (carried + np.cumsum(np.exp(c) * innovation[start:stop], axis=0))
        carried = out[stop - 1]
    return out.reshape(white.shape)


def star_tracker_noise(n, dt_s, st_cfg, correlation_time_s, rng, scale=None, turned_rad=None):
    """Body-frame attitude noise (rad), anisotropic about a boresight: white noise of sigma across
    and about it (AR(1) as a whole with the hidden effect ``st_correlation_time_s``), times
    ``scale`` per sample, plus the Gauss-Markov part that ``gm_*`` declares, unscaled. With
    ``gm_clock_s_per_rad`` (kappa) that part's clock runs on the angle turned too: each step ``dt + kappa
    dtheta`` (``turned_rad``: the body's turn from the previous sample), an error that holds while the
    body rests and changes as it turns, over a correlation angle ``gm_tau_s / kappa``."""
    boresight = np.asarray(st_cfg["boresight_body"], dtype=float)
    boresight /= np.linalg.norm(boresight)
    helper = np.eye(3)[np.argmin(np.abs(boresight))]
    e1 = np.cross(boresight, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(boresight, e1)

    def frame(unit, cross_arcsec, about_arcsec):
        cross, about = arcsec_to_rad(cross_arcsec), arcsec_to_rad(about_arcsec)
        return cross * (unit[:, :1] * e1 + unit[:, 1:2] * e2) + about * unit[:, 2:] * boresight

    white = rng.normal(size=(n, 3))
    if correlation_time_s > 0:
        white = gauss_markov(white, dt_s, correlation_time_s)
    noise = frame(white, st_cfg["sigma_cross_arcsec"], st_cfg["sigma_about_arcsec"])
    if scale is not None:
        noise = noise * scale[:, None]
    gm_cross, gm_about, tau = (st_cfg.get(k, 0.0) for k in ("gm_sigma_cross_arcsec", "gm_sigma_about_arcsec", "gm_tau_s"))
    if tau > 0 and (gm_cross or gm_about):
        clock = st_cfg.get("gm_clock_s_per_rad", 0.0)
        steps = dt_s + clock * np.asarray(turned_rad, dtype=float) if clock else dt_s
        noise = noise + frame(gauss_markov(rng.normal(size=(n, 3)), steps, tau), gm_cross, gm_about)
    return noise


def run(scenario_path, outdir, seed=None):
    """``gyrocal simulate``: write ``OUTDIR/campaign/`` and ``OUTDIR/truth.json``."""
    scenario = load_scenario(scenario_path)
    campaign, truth = simulate(scenario, seed)
    outdir = Path(outdir)
    write_campaign(campaign, outdir / "campaign")
    write_text(json.dumps(truth, indent=2, sort_keys=True), outdir / "truth.json")
    return campaign, truth
