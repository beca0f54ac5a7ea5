"""Plan before flying: what a planned campaign will tell, before any data exist.

No noise is drawn and nothing is sampled. The plan's campaign is the simulator's trajectory
(`simulate`) with every noise, bias, limit-cycle rate and hidden effect at zero, so the
parameters sit at their prior mean; the preprocessing, the linearised model (`errormodel`), the
noise model (`noise`) and the likelihood (`likelihood`) are gyrocal's own, so the information is
the one the WLS and the posterior use, with the nuisance (initial attitude error, biases)
integrated out, at the stated noise: where the scenario's star tracker has a Gauss-Markov part, with
it (`markov`), as a run whose model has ``st_correlated_noise`` would fit it.
From it: each parameter's predicted posterior sd and its Cramér-Rao bound without the prior, the
same for each channel's identifiable combinations (``sf_mean``, ``sf_asym``: `combinations`) and
whether each will be resolved, the pairs the plan cannot separate, and for each library effect the
model lacks, the smallest magnitude the diagnostics' structure test (`diagnostics.rank`,
`diagnostics.misfit_checks`) would detect `DETECTION_POWER` of the time.
"""

import copy
import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats as sps
from scipy.optimize import brentq

from gyrocal.criticism.diagnostics import COLLINEAR_FRACTION
from gyrocal.inference import errormodel
from gyrocal.inference.fit import identification
from gyrocal.inference.fit.identification import CORRELATION_MAX, confounded_pairs
from gyrocal.inference.fit.likelihood import Stats, campaign_stats
from gyrocal.inference.noise import covariance
from gyrocal.io.campaign_yaml import GM_CLOCK_KEY
from gyrocal.io.scenario import STAR_TRACKER_GM
from gyrocal.io.yamlfile import load_yaml
from gyrocal.maneuvers import preprocess
from gyrocal.model import combinations, effects
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import AXES, arcsec_to_rad
from gyrocal.simulation import simulate

__all__ = [
    "CONFIG_SECTIONS",
    "DETECTION_POWER",
    "NULL_FRACTION",
    "Plan",
    "comparison",
    "crlb_sd",
    "detectable_noncentrality",
    "detection_table",
    "figure",
    "information",
    "noise_variances",
    "noncentrality",
    "plan",
    "planned_maneuvers",
    "predicted_covariance",
    "quiet",
    "read_config",
    "read_scenario",
    "report",
    "stated_noise"
]

DETECTION_POWER = 0.9
"""An effect counts as detectable at the magnitude the structure test flags this often."""

NULL_FRACTION = 1e-12
"""An eigenvalue of the prior-scaled information below this share of the largest is a direction the
data do not inform at all: the Cramér-Rao bound of a parameter that loads on it is infinite."""


def quiet(scenario: dict) -> dict:
    """The scenario with no noise, biases, limit-cycle rates, invalid samples or hidden effects, its
    parameters at the prior mean (zero): the noise-free trajectory of the plan."""
    out = copy.deepcopy(scenario)
    out["truth"] = {}
    out["gyro"].update(arw_deg_sqrt_h=0.0, pulse_arcsec=0.0, bias_sd_deg_h=0.0)
    out["star_tracker"].update(sigma_cross_arcsec=0.0, sigma_about_arcsec=0.0, invalid_fraction=0.0,
                               **dict.fromkeys(STAR_TRACKER_GM, 0.0))
    out["maneuver_defaults"]["uncontrolled_rate_deg_s"] = 0.0
    out["effects"] = dict.fromkeys(out["effects"], 0.0)
    return out


def planned_maneuvers(scenario: dict) -> list:
    """The plan's maneuvers as the preprocessing would cut them from its noise-free campaign, with the
    Gauss-Markov part's clock the scenario's (``star_tracker.gm_clock_s_per_rad``), as a campaign.yaml
    that states it gives them."""
    campaign, _ = simulate.simulate(quiet(scenario))
    clock = float(scenario["star_tracker"].get(GM_CLOCK_KEY) or 0.0)
    return [dataclasses.replace(preprocess.slice_maneuver(campaign, m.id), gm_clock_s_per_rad=clock)
            for m in campaign.maneuvers]


def stated_noise(scenario: dict, noise_defaults: dict) -> dict:
    """The noise knowledge a run would be given: the scenario's, as its campaign.yaml states it; where its
    star tracker has a Gauss-Markov part, its sds across and about the boresight and its correlation
    time too (the scenario's ``gm_sigma_cross_arcsec``, ``gm_sigma_about_arcsec``, ``gm_tau_s``; its clock
    `planned_maneuvers` carries)."""
    st = scenario["star_tracker"]
    stated = covariance.noise_knowledge({"star_tracker": st, "gyro": scenario["gyro"]}, noise_defaults)
    gm = {k: float(st.get(k) or 0.0) for k in STAR_TRACKER_GM}
    if gm["gm_tau_s"] > 0 and gm["gm_sigma_cross_arcsec"] ** 2 + gm["gm_sigma_about_arcsec"] ** 2 > 0:
        stated.update(gm)
    return stated


def noise_variances(stated: dict) -> tuple:
    """``(tau_s, variances)``: the covariance components' variances (SI, `covariance.variances`' keys) of
    `stated_noise`'s noise, with the Gauss-Markov part's across and about the boresight each its own
    (a run's correlated model takes one share for both; the plan takes the scenario's noise as it is);
    ``tau_s`` 0 without one."""
    variances = covariance.variances(covariance.log_sigma_of(stated))
    tau_s = float(stated.get("gm_tau_s", 0.0))
    if tau_s > 0:
        variances.update(gm_cross=float(arcsec_to_rad(stated["gm_sigma_cross_arcsec"])) ** 2,
                         gm_about=float(arcsec_to_rad(stated["gm_sigma_about_arcsec"])) ** 2)
    return tau_s, variances


def information(maneuvers, spec: ModelSpec, stated: dict) -> Stats:
    """The campaign's `Stats` at the prior mean and the stated noise (`noise_variances`: with its
    Gauss-Markov part where it has one, `markov`); ``A`` is the Fisher information of the spec's
    parameters (SI) with each maneuver's nuisance integrated out."""
    zeros = np.zeros(len(spec.channels))
    lins = [errormodel.linearize(d, spec, spec.prior_mean_si, zeros) for d in maneuvers]
    tau_s, variances = noise_variances(stated)
    return campaign_stats([covariance.build(lin, stated["boresight_body"], tau_s) for lin in lins], variances)


def predicted_covariance(A: np.ndarray, prior_sd_si: np.ndarray) -> np.ndarray:
    """Posterior covariance of the linear Gaussian model: ``(A + diag(prior_sd^-2))^-1``, solved in
    prior-scaled coordinates (ppm and arcsec columns differ by orders of magnitude in SI)."""
    scaled = A * np.outer(prior_sd_si, prior_sd_si) + np.eye(len(A))
    return np.linalg.inv(scaled) * np.outer(prior_sd_si, prior_sd_si)


def crlb_sd(A: np.ndarray, free: np.ndarray, prior_sd_si: np.ndarray) -> np.ndarray:
    """Cramér-Rao bound of each free parameter without the prior (the WLS sd); infinite where the
    parameter loads on a direction the data leave uninformed, NaN for prior-only parameters."""
    out = np.full(len(A), np.nan)
    idx = np.flatnonzero(free)
    if not len(idx) or not np.any(A[np.ix_(idx, idx)]):
        out[idx] = np.inf
        return out
    scale = prior_sd_si[idx]
    values, vectors = np.linalg.eigh(A[np.ix_(idx, idx)] * np.outer(scale, scale))
    null = values <= NULL_FRACTION * values.max()
    var = (vectors[:, ~null] ** 2 / values[~null]) @ np.ones((~null).sum())
    blind = np.linalg.norm(vectors[:, null], axis=1) > 1e-6
    out[idx] = np.where(blind, np.inf, np.sqrt(var) * scale)
    return out


def _schur(A, base, cand):
    """Information of columns ``cand`` left once columns ``base`` are fitted (flat prior)."""
    A_bb, A_cb = A[np.ix_(base, base)], A[np.ix_(cand, base)]
    return A[np.ix_(cand, cand)] - A_cb @ np.linalg.lstsq(A_bb, A_cb.T, rcond=1e-12)[0]


def noncentrality(A: np.ndarray, base, cand, delta_si) -> tuple:
    """Noncentrality per unit magnitude of the structure test of columns ``cand`` given ``base``
    (`diagnostics.conditional_drop`) when the data carry ``delta_si`` along them, and the
    degrees of freedom it tests (directions the model does not already span)."""
    base, cand = np.asarray(base, dtype=int), np.asarray(cand, dtype=int)
    scale = np.sqrt(np.maximum(np.diag(A)[cand], 1e-300))
    values, vectors = np.linalg.eigh(_schur(A, base, cand) / np.outer(scale, scale))
    keep = values > COLLINEAR_FRACTION
    loading = vectors[:, keep].T @ (scale * np.asarray(delta_si, dtype=float))
    return float(np.sum(values[keep] * loading**2)), int(keep.sum())


def detectable_noncentrality(df_tested: int, df: int, log10_p_min: float, power: float = DETECTION_POWER) -> float:
    """The noncentrality at which a chi-square statistic on ``df`` directions exceeds the test's
    critical value (p = 10^log10_p_min on ``df_tested`` degrees of freedom) with ``power``."""
    critical = sps.chi2.isf(10.0**log10_p_min, df_tested)
    return brentq(lambda lam: sps.ncx2.sf(critical, df, lam) - power, 1e-9, 100.0 * critical + 100.0)


@dataclass
class Plan:
    """What one planned campaign predicts for one model."""

    name: str
    spec: ModelSpec
    """The model with the parameters the plan cannot inform marked prior-only."""
    cov: np.ndarray
    """Predicted posterior covariance (SI)."""
    crlb_sd: np.ndarray
    pairs: list
    detection: pd.DataFrame
    information: np.ndarray | None = None
    """The Fisher information of the spec's parameters (SI), prior-only columns zeroed."""
    noise: dict | None = None
    """The noise it assumed (`stated_noise`), in the contract's units."""

    def noise_line(self) -> str:
        """The assumed noise in one line: the reference's white sds, its Gauss-Markov part's and their
        correlation time where it has one, and the ARW."""
        n = self.noise or {}
        if not n:
            return ""
        clock = (f" on a clock of time and {n[GM_CLOCK_KEY]:g} s a radian turned"
                 if n.get(GM_CLOCK_KEY) else "")
        gm = (f"; Gauss-Markov {n['gm_sigma_cross_arcsec']:.3g} / {n['gm_sigma_about_arcsec']:.3g} arcsec over "
              f"{n['gm_tau_s']:g} s{clock}" if n.get("gm_tau_s") else "")
        return (f"-- noise: reference {n['sigma_cross_arcsec']:.3g} / {n['sigma_about_arcsec']:.3g} arcsec white "
                f"across / about the boresight{gm}; ARW {n['arw_deg_sqrt_h']:.3g} deg/sqrt(h)")

    def mounting_separability(self) -> pd.DataFrame:
        """`combinations.mounting_separability` of the predicted covariance: what an estimated
        reference mounting (``mounting: estimate``) would take up of the misalignments."""
        cov_unit = self.cov / np.outer(self.spec.si_per_unit, self.spec.si_per_unit)
        frame = pd.DataFrame(combinations.mounting_separability(cov_unit, self.spec),
                             columns=["axis", "kind", "combination", "ratio_fitted", "ratio_mounting_free"])
        return frame.assign(separable=frame["ratio_mounting_free"] <= combinations.RESOLVED_RATIO_MAX)

    def table(self) -> pd.DataFrame:
        """Per parameter, in its unit: predicted posterior sd, Cramér-Rao bound, prior sd, their
        ratio, whether it will be resolved (`combinations.RESOLVED_RATIO_MAX`), why it is
        prior-only, and what it is confounded with; then per channel its combinations ``sf_mean``
        and ``sf_asym``, their sd ``sqrt(a' C a)`` of the predicted covariance."""
        spec = self.spec
        sd = spec.to_unit(np.sqrt(np.diag(self.cov)))
        prior = np.array([p.prior_sd for p in spec.parameters])
        partners = {label: [] for label in spec.labels}
        for a, b, r in self.pairs:
            partners[a].append(f"{b} ({r:+.2f})")
            partners[b].append(f"{a} ({r:+.2f})")
        params = pd.DataFrame({
            "plan": self.name, "channel": [p.owner for p in spec.parameters],
            "parameter": [p.name for p in spec.parameters], "unit": spec.units,
            "predicted_sd": sd, "crlb_sd": spec.to_unit(self.crlb_sd), "prior_sd": prior,
            "sd_over_prior": sd / prior, "prior_only": [p.prior_only for p in spec.parameters],
            "confounded_with": ["; ".join(partners[label]) for label in spec.labels]})
        combos = combinations.scale_combinations(spec)
        if combos:
            cov_unit = self.cov / np.outer(spec.si_per_unit, spec.si_per_unit)
            c_sd, c_prior, ratio = combinations.prior_relative(cov_unit, combinations.weights(combos), prior)
            crlb = (combinations.crlb_sd(self.information, spec, combos) if self.information is not None
                    else np.full(len(combos), np.nan))
            params = pd.concat([params, pd.DataFrame({
                "plan": self.name, "channel": [c.owner for c in combos], "parameter": [c.name for c in combos],
                "unit": [c.unit for c in combos], "predicted_sd": c_sd, "crlb_sd": crlb, "prior_sd": c_prior,
                "sd_over_prior": ratio, "prior_only": ["every part prior-only" if c.prior_only else "" for c in combos],
                "confounded_with": ""})], ignore_index=True)
        params.insert(params.columns.get_loc("prior_only"), "resolved",
                      params["sd_over_prior"] <= combinations.RESOLVED_RATIO_MAX)
        return params


def _applicable(effect, data) -> str:
    """Empty when the effect can be evaluated on the plan's maneuvers, else why not."""
    try:
        errormodel.effect_derivatives(effect, errormodel.view(data))
        return ""
    except ValueError as exc:
        return str(exc)


def _confounder(A, spec, base, cand, delta) -> str:
    """The model effect whose parameters alone explain most of the candidate's information."""
    total = delta @ A[np.ix_(cand, cand)] @ delta
    if total <= 0:
        return "its columns carry no information once the nuisance (initial attitude, biases) is fitted"
    shares = {}
    for name in spec.effect_names:
        group = [i for i in base if spec.parameters[i].effect == name]
        if group:
            shares[name] = 1.0 - delta @ _schur(A, group, cand) @ delta / total
    best = max(shares, key=shares.get)
    return f"{shares[best]:.3%} of its information is explained by the model's {best}"


def detection_table(A, spec: ModelSpec, augmented: ModelSpec, skipped: dict, log10_p_min: float) -> pd.DataFrame:
    """Per candidate effect and parameter: the smallest magnitude (the same on every channel, in the
    parameter's unit) that the structure test flags `DETECTION_POWER` of the time, or why none."""
    n = len(spec)
    base = list(np.flatnonzero(spec.free))
    rows = []
    extras = augmented.parameters[n:]
    for effect in dict.fromkeys(p.effect for p in extras):
        columns = [n + i for i, p in enumerate(extras) if p.effect == effect]
        for name in dict.fromkeys(augmented.parameters[i].name for i in columns):
            cand = [i for i in columns if augmented.parameters[i].name == name]
            p = augmented.parameters[cand[0]]
            delta = np.zeros(len(columns))
            delta[[columns.index(i) for i in cand]] = p.si_per_unit
            lam, df = noncentrality(A, base, columns, delta)
            magnitude, why = np.inf, ""
            if df == 0 or lam <= 0:
                why = "confounded: " + _confounder(A, augmented, base, columns, delta)
            else:
                magnitude = float(np.sqrt(detectable_noncentrality(len(columns), df, log10_p_min) / lam))
                if magnitude > p.bound:
                    why = (f"beyond its physical bound {p.bound:g} {p.unit}: "
                           + _confounder(A, augmented, base, columns, delta))
            rows.append({"effect": effect, "parameter": name, "unit": p.unit, "columns": len(columns),
                         "tested_directions": df, "detectable_magnitude": magnitude, "bound": p.bound,
                         "detectable": not why, "why_not": why})
    for effect, why in skipped.items():
        rows.append({"effect": effect, "parameter": "", "unit": "", "columns": 0, "tested_directions": 0,
                     "detectable_magnitude": np.inf, "bound": np.nan, "detectable": False, "why_not": why})
    return pd.DataFrame(rows)


def plan(scenario: dict, cfg: dict, model: str = "baseline", name: str = "") -> Plan:
    """Predict what a planned campaign (a scenario, `simulate.load_scenario`) will tell under
    ``cfg`` (the gyrocal config: models, plugins, priors, noise defaults, diagnostics)."""
    if model not in cfg["models"]:
        raise ValueError(f"model {model!r} is not in the config's models: {sorted(cfg['models'])}")
    known = effects.known(cfg.get("plugins"))
    plugins = {k: e for k, e in known.items() if k not in effects.LIBRARY}
    maneuvers = planned_maneuvers(scenario)
    spec = ModelSpec.build(model, effects.resolve(model, cfg["models"][model], plugins), maneuvers[0].channels)
    spec = spec.with_sensor_class((scenario.get("gyro") or {}).get("sensor_class")).with_priors(cfg["priors"])
    stated = stated_noise(scenario, cfg["noise"])
    spec = spec.with_prior_only(identification.unflown(maneuvers, spec, stated))
    candidates, skipped = [], {}
    for effect in known.values():
        if effect.name in spec.effect_names or effect.core:
            continue
        if effect.noise:
            skipped[effect.name] = "a noise-model effect: it is tested by the whiteness check, not the structure test"
            continue
        why = _applicable(effect, maneuvers[0])
        if why:
            skipped[effect.name] = why
        else:
            candidates.append(effect)
    augmented = spec.augmented(candidates)
    stats = information(maneuvers, augmented, stated)
    n = len(spec)
    weak = identification.uninformed(Stats(stats.A[:n, :n], stats.b[:n], stats.c, stats.logdet, stats.n), spec)
    spec = spec.with_prior_only(weak)
    augmented = spec.augmented(candidates)
    A = stats.A.copy()
    dropped = np.flatnonzero(~spec.free)
    A[dropped, :] = 0.0
    A[:, dropped] = 0.0
    cov = predicted_covariance(A[:n, :n], spec.prior_sd_si)
    return Plan(name or scenario["name"], spec, cov, crlb_sd(A[:n, :n], spec.free, spec.prior_sd_si),
                confounded_pairs(cov, spec.free, spec.labels),
                detection_table(A, spec, augmented, skipped, cfg["diagnostics"]["structure_log10_p_min"]), A[:n, :n],
                stated)


CONFIG_SECTIONS = ("models", "priors", "noise", "diagnostics")
"""The config sections a plan reads (models and plugins, priors, noise defaults, the structure test's threshold)."""


def read_config(path) -> dict:
    """The gyrocal config a plan uses; a missing file or section is named."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no gyrocal config there; pass --config PATH/TO/config.yaml")
    cfg = load_yaml(path) or {}
    if not isinstance(cfg, dict):
        raise ValueError(f"{path}: a gyrocal config is a mapping of sections {list(CONFIG_SECTIONS)} and more")
    missing = [s for s in CONFIG_SECTIONS if s not in cfg]
    if missing:
        raise ValueError(f"{path}: missing section(s) {missing}")
    if "structure_log10_p_min" not in cfg["diagnostics"]:
        raise ValueError(f"{path}: diagnostics.structure_log10_p_min is missing")
    return cfg


def read_scenario(path) -> dict:
    """A scenario (`simulate.load_scenario`) whose maneuvers a plan can fly: each names an id and an
    axis with a direction "+" or "-" (a single-axis slew), a unit vector ``axis: [x, y, z]`` (an
    eigen-axis slew) or a body rate vector ``rate_deg_s: [x, y, z]`` with its ``duration_s`` (a
    tumble); a bad entry is named with its file and field."""
    scenario = simulate.load_scenario(path)
    for i, m in enumerate(scenario["maneuvers"]):
        where = f"{path}: maneuvers[{i}]"
        if "id" not in m:
            raise ValueError(f"{where}: missing field 'id'")
        if isinstance(m.get("rate_deg_s"), list):
            if "duration_s" not in m:
                raise ValueError(f"{where}: a tumble (rate_deg_s: [x, y, z]) needs its duration_s")
            continue
        if "axis" not in m:
            raise ValueError(f"{where}: missing field 'axis'")
        if isinstance(m["axis"], list):
            if abs(np.linalg.norm(m["axis"]) - 1.0) > 1e-3:
                raise ValueError(f"{where}.axis: {m['axis']} is not a unit vector in body axes")
            continue
        if "direction" not in m:
            raise ValueError(f"{where}: missing field 'direction'")
        if m["axis"] not in AXES:
            raise ValueError(f"{where}.axis: {m['axis']!r} is not one of {list(AXES)}")
        if m["direction"] not in ("+", "-"):
            raise ValueError(f"{where}.direction: {m['direction']!r}; a planned maneuver turns \"+\" or \"-\"")
    return scenario


def comparison(first: Plan, second: Plan) -> tuple:
    """Two plans side by side: per parameter the predicted sd of each and their ratio (B over A),
    and per effect each one's detectable magnitude."""
    params = _side_by_side(first.table(), second.table(), ["channel", "parameter", "unit"], "predicted_sd")
    params["b_over_a"] = params["predicted_sd_b"] / params["predicted_sd_a"]
    found = _side_by_side(first.detection, second.detection, ["effect", "parameter", "unit"], "detectable_magnitude")
    return params, found


def _side_by_side(a, b, keys, column):
    """``column`` of two tables joined on ``keys``, in A's row order, then B's rows A lacks."""
    order = pd.concat([a[keys], b[keys]]).drop_duplicates()
    return (order.merge(a[keys + [column]], on=keys, how="left")
            .merge(b[keys + [column]], on=keys, how="left", suffixes=("_a", "_b")))


def figure(plans):
    """Predicted posterior sd of every parameter, one panel per unit, one marker per plan."""
    import matplotlib.pyplot as plt
    tables = [p.table() for p in plans]
    units = list(dict.fromkeys(tables[0]["unit"]))
    fig, axes = plt.subplots(len(units), 1, figsize=(9, 3.2 * len(units)), squeeze=False)
    for ax, unit in zip(axes[:, 0], units):
        for k, (p, table) in enumerate(zip(plans, tables)):
            rows = table[table["unit"] == unit]
            x = np.arange(len(rows)) + 0.15 * (k - (len(plans) - 1) / 2)
            ax.plot(x, rows["predicted_sd"], "o", label=p.name)
        labels = tables[0].loc[tables[0]["unit"] == unit, ["channel", "parameter"]].agg(".".join, axis=1)
        ax.set_xticks(np.arange(len(labels)), labels, rotation=60, ha="right", fontsize=7)
        ax.set_yscale("log")
        ax.set_ylabel(f"predicted sd ({unit})")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Predicted posterior sd per parameter (prior-only parameters sit at their prior sd)")
    fig.tight_layout()
    return fig


def report(plans, threshold: float = CORRELATION_MAX) -> str:
    """What `gyrocal plan` prints: per plan the parameter table, the pairs it cannot separate and
    the detection table; with two plans, the comparison."""
    out = []
    for p in plans:
        table = p.table().drop(columns=["plan", "confounded_with"])
        out += [f"== plan {p.name}, model {p.spec.model}: predicted posterior sd (crlb_sd: without the prior; "
                f"sf_mean = (sf_pos + sf_neg) / 2, sf_asym = sf_pos - sf_neg; resolved: sd_over_prior <= "
                f"{combinations.RESOLVED_RATIO_MAX:g})",
                *([p.noise_line()] if p.noise else []),
                table.to_string(index=False, float_format=lambda v: f"{v:.4g}")]
        pairs = [f"  {a} ~ {b}: correlation {r:+.3f}" for a, b, r in p.pairs]
        out += [f"-- pairs the plan cannot separate (|correlation| > {threshold:g}):"] + (pairs or ["  none"])
        mounting = p.mounting_separability()
        if len(mounting):
            out += ["-- if the reference's mounting is estimated from these data (mounting: estimate): sd over the "
                    "prior's of each misalignment combination, as fitted and with the mounting free (separable: "
                    f"<= {combinations.RESOLVED_RATIO_MAX:g})",
                    mounting.to_string(index=False, float_format=lambda v: f"{v:.3f}")]
        out += [f"-- smallest magnitude the structure test detects {DETECTION_POWER:.0%} of the time "
                "(the same on every channel):",
                p.detection.to_string(index=False, float_format=lambda v: f"{v:.4g}")]
    if len(plans) == 2:
        params, found = comparison(*plans)
        out += [f"== A = {plans[0].name}, B = {plans[1].name}: predicted sd side by side",
                params.to_string(index=False, float_format=lambda v: f"{v:.4g}"),
                "-- detectable magnitude side by side",
                found.to_string(index=False, float_format=lambda v: f"{v:.4g}")]
    return "\n".join(out)
