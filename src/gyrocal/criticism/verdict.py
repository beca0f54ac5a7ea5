"""The GO/NO-GO verdict: each check behind it as a `Finding`, and the verdict a pure function of them.

The checks apply to the channel model's terms (what the uplinked correction is made of), with
the thresholds of the config's ``convergence``, ``report`` (``max_ci_width_<unit>``, and
``physical_bound_<unit>`` where set, else the campaign's sensor class's, `physical_bounds`) and
``model_choice`` sections. The report renders these findings;
``verdict.json`` holds `verdict` of them.
"""

import numpy as np
import pandas as pd

from gyrocal.criticism import modelchoice
from gyrocal.criticism.uplinked import at_uplink
from gyrocal.finding import Finding
from gyrocal.inference.fit.classic import hold_windows
from gyrocal.inference.fit.operating import operating_params
from gyrocal.io.calibration import core_rows, posterior_mean_extras, posterior_mean_params
from gyrocal.maneuvers import preprocess
from gyrocal.model import sensorclass
from gyrocal.model.units import AXES, rad_to_arcsec

__all__ = ["RANKED_SHOWN", "bounds_check", "checks", "convergence_check", "correction_check", "correction_effect",
           "estimate_effect", "informed_check", "informed_core", "interval_check", "misfit_check", "physical_bounds",
           "verdict", "width_limits"]


def width_limits(rcfg: dict, spec) -> dict:
    """The widest acceptable 95 % interval of each channel-model unit (``max_ci_width_<unit>``)."""
    return {unit: rcfg[f"max_ci_width_{unit}"] for unit in set(spec.units[spec.core])}


def informed_core(spec) -> list:
    """Labels of the channel-model terms the data inform (prior-only ones have their own check)."""
    return [p.label for p in spec.parameters[spec.core] if not p.prior_only]


def correction_effect(maneuvers, params_by_maneuver, nominal_by_maneuver) -> pd.DataFrame:
    """Attitude error left at the end of every maneuver and channel set, before the
    correction (nominal parameters) and after it (the estimate); both with the estimated
    biases removed, so what differs is the uplinked scale factors and misalignments. A maneuver
    with no reference sample in a hold (one that turns throughout, or a sparse reference)
    takes its first or last reference sample instead."""
    rows = []
    for data, params, nominal in zip(maneuvers, params_by_maneuver, nominal_by_maneuver):
        before_mask, after_mask = hold_windows(data)
        if not before_mask.any():
            before_mask = np.arange(len(data.st_time)) == 0
        if not after_mask.any():
            after_mask = np.arange(len(data.st_time)) == len(data.st_time) - 1
        for s, channel_set in enumerate(data.sets):
            before = preprocess.end_of_rotation_error(data, channel_set, nominal, before_mask, after_mask)
            after = preprocess.end_of_rotation_error(data, channel_set, params, before_mask, after_mask)
            rows.append({"maneuver": data.id, "set": "+".join(channel_set), "in loop": s == 0,
                         **{f"before {a} (arcsec)": round(float(rad_to_arcsec(before[i])), 1) for i, a in enumerate(AXES)},
                         **{f"after {a} (arcsec)": round(float(rad_to_arcsec(after[i])), 1) for i, a in enumerate(AXES)},
                         "before norm": float(rad_to_arcsec(np.linalg.norm(before))),
                         "after norm": float(rad_to_arcsec(np.linalg.norm(after)))})
    return pd.DataFrame(rows)


def estimate_effect(maneuvers, spec, calibration: pd.DataFrame, biases, shift_map: np.ndarray) -> pd.DataFrame:
    """`correction_effect` of the uplink, the posterior mean of ``calibration`` with its scale factors
    at the campaign's rates (``shift_map``: `operating_map` of these maneuvers and biases), against the
    nominal parameters, each maneuver with its own estimated biases (``biases``, in its order)."""
    shift = shift_map @ posterior_mean_extras(spec, calibration)
    params = [operating_params(posterior_mean_params(spec, calibration, biases[m]), shift) for m in range(len(maneuvers))]
    nominal = [spec.channel_params(np.zeros(len(spec)), biases[m]) for m in range(len(maneuvers))]
    return correction_effect(maneuvers, params, nominal)


def convergence_check(calibration: pd.DataFrame, spec, sampler: dict, conv: dict) -> Finding:
    """Every channel-model term has r_hat below ``r_hat_max`` and bulk ESS at least ``ess_bulk_min``,
    and the chains are long enough for their autocorrelation (``sampler.json``)."""
    base = core_rows(spec, calibration)
    bad = base[(base["r_hat"] >= conv["r_hat_max"]) | (base["ess_bulk"] < conv["ess_bulk_min"])]
    passed = bad.empty and sampler["converged"]
    if passed:
        why = "every parameter has r_hat < {} and bulk ESS >= {}".format(conv["r_hat_max"], conv["ess_bulk_min"])
    else:
        why = "not converged: " + (", ".join(f"{r.channel}.{r.parameter} (r_hat {r.r_hat:.3f}, ESS {r.ess_bulk:.0f})"
                                             for r in bad.itertuples()) or "chains shorter than the autocorrelation limit")
    details = {}
    if base["r_hat"].notna().any():
        worst = base.loc[base["r_hat"].idxmax()]
        details = {"figure": float(worst["r_hat"]), "threshold": float(conv["r_hat_max"]),
                   "where": f"{worst['channel']}.{worst['parameter']}"}
    return Finding.judged("converged", passed, why,
                          action="" if passed else "run longer chains (sampler.max_steps)", **details)


RANKED_SHOWN = 3
"""How many top-ranked explanations a misfit names where none is significant."""


def misfit_check(diagnostics: dict, log10_p_min: float) -> Finding:
    """The reviewed model's residuals are consistent with its noise model (``diagnostics.json``);
    a misfit names the failed checks and the best explanation, where its score test is significant
    at ``log10_p_min`` (the config's ``diagnostics.structure_log10_p_min``); where none is, it says so
    and names the top-ranked ones with their p."""
    failed = [c for c in diagnostics["checks"] if not c["passed"]]
    if not failed:
        return Finding.judged("no misfit", not diagnostics["misfit"], "the residuals are consistent with the noise model")
    ranking = diagnostics["ranking"]
    why = "misfit: " + "; ".join(f"{c['check']}: {c['why']}" for c in failed)
    best = ranking[0] if ranking else None
    if best is not None and best["log10_p"] < log10_p_min:
        why += (f". Best explanation: {best['kind']} {best['name']} (log10 p = {best['log10_p']:.1f}, "
                f"significant below {log10_p_min:g})")
        action = (f"add a variant with {best['name']} (models:)" if best["kind"] == "effect" else
                  f"model what follows the {best['name']} signature (an effect under plugins:)")
    else:
        top = ", ".join(f"{r['kind']} {r['name']} (log10 p = {r['log10_p']:.1f})" for r in ranking[:RANKED_SHOWN])
        why += (f". No effect or signature explains the misfit significantly (log10 p below {log10_p_min:g})"
                + (f"; the top-ranked: {top}" if top else ""))
        action = ("look at the residual figures for what the ranking lacks: a noise the stated one understates, "
                  "or an effect outside the library (plugins:)")
    return Finding.judged("no misfit", not diagnostics["misfit"], why, action=action)


def informed_check(spec) -> Finding:
    """Every parameter has a maneuver that informs it; a prior-only core term leaves its channel
    without a correction."""
    uninformed = [p for p in spec.parameters if p.prior_only]
    if not uninformed:
        return Finding.judged("every parameter informed by the data", True,
                              "every parameter has a maneuver that informs it")
    channels = sorted({p.owner for p in uninformed if p.core})
    why = ("prior-only (the posterior is the prior): " + "; ".join(f"{p.label} ({p.prior_only})" for p in uninformed)
           + (f". No correction for {', '.join(channels)}" if channels else ""))
    return Finding.judged("every parameter informed by the data", False, why, where=", ".join(channels),
                          action="fly the missing maneuvers (gyrocal plan names them)")


def interval_check(calibration: pd.DataFrame, spec, rcfg: dict, flown: pd.DataFrame | None = None) -> Finding:
    """Every informed channel-model term's 95 % interval, as uplinked, is narrower than the limit of its
    unit; the figure is the widest interval relative to its limit. ``flown``
    (`gyrocal.criticism.uplinked.uplinked_intervals`, for a model whose scale factor changes with the
    rate) holds the scale factors at the campaign's rates: the uplink is made of those, not of the
    zero-rate intercepts, which such a model leaves wide where the campaign turned at one rate."""
    labels, limits = informed_core(spec), width_limits(rcfg, spec)
    at_rates = flown is not None and not flown.empty
    calibration = at_uplink(calibration, flown)
    widths = modelchoice.interval_widths(calibration, labels, limits)
    wide = [w for w in widths if w["width"] > w["limit"]]
    which = " (the scale factors at the campaign's rates, as uplinked)" if at_rates else ""
    why = (f"every 95 % interval{which} is narrower than {rcfg['max_ci_width_ppm']} ppm / "
           f"{rcfg['max_ci_width_arcsec']} arcsec" if not wide
           else f"too wide{which}: " + ", ".join(f"{w['label']} ({w['width']:.1f} {w['unit']})" for w in wide))
    details = {}
    if widths:
        worst = max(widths, key=lambda w: w["width"] / w["limit"])
        details = {"figure": worst["width"], "threshold": worst["limit"], "unit": worst["unit"],
                   "where": worst["label"]}
    return Finding.judged("intervals narrow enough", not wide, why, **details,
                          action="" if not wide else "fly more or longer maneuvers that excite these terms (gyrocal plan)")


def physical_bounds(rcfg: dict, sensor_class: str | None) -> dict:
    """``{unit: bound}`` a GO accepts of the channel-model terms: the campaign's gyro sensor class's
    (`gyrocal.model.sensorclass.SensorClass.physical_bounds`; None: a DTG's), unless the config's
    ``report.physical_bound_<unit>`` sets one (a number, not null)."""
    bounds = sensorclass.limits(sensor_class).physical_bounds()
    return {unit: bound if rcfg.get(f"physical_bound_{unit}") is None else rcfg[f"physical_bound_{unit}"]
            for unit, bound in bounds.items()}


def _number(x) -> str:
    """A bound as the config would write it: 20000, not 20000.0."""
    return f"{x:g}" if float(x) != int(x) else str(int(x))


def bounds_check(calibration: pd.DataFrame, spec, bounds: dict) -> Finding:
    """Every channel-model term's posterior mean is within the physical bound of its unit
    (``bounds``, `physical_bounds`); the figure is the largest relative to its bound."""
    base = core_rows(spec, calibration)
    bound = np.array([bounds[unit] for unit in base["unit"]], dtype=float)
    size = np.abs(base["mean"].to_numpy())
    out = base[size > bound]
    why = (f"every estimate is within {_number(bounds['ppm'])} ppm / {_number(bounds['arcsec'])} arcsec"
           if out.empty else "outside: " + ", ".join(f"{r.channel}.{r.parameter} = {r.mean:.0f} {r.unit}"
                                                     for r in out.itertuples()))
    details = {}
    if len(base):
        k = int(np.argmax(size / bound))
        worst = base.iloc[k]
        details = {"figure": float(size[k]), "threshold": float(bound[k]), "unit": worst["unit"],
                   "where": f"{worst['channel']}.{worst['parameter']}"}
    return Finding.judged("within physical bounds", out.empty, why, **details,
                          action="" if out.empty else "check the channel mapping and signs of the input")


def correction_check(effect_table: pd.DataFrame) -> Finding:
    """The correction reduces the end-of-maneuver attitude error on every maneuver and channel
    set (`correction_effect`); the figure is the worst ratio of the error after to before."""
    worse = effect_table[effect_table["after norm"] >= effect_table["before norm"]]
    why = ("the correction reduces the end-of-maneuver attitude error on every maneuver and channel set"
           if worse.empty else "not reduced on: " + ", ".join(
               f"{r['maneuver']} with {r['set']} ({r['before norm']:.1f} -> {r['after norm']:.1f} arcsec)"
               for r in worse.to_dict("records")))
    details = {}
    if len(effect_table):
        before, after = effect_table["before norm"].to_numpy(), effect_table["after norm"].to_numpy()
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(before > 0, after / before, np.where(after > 0, np.inf, 1.0))
        k = int(np.argmax(ratio))
        row = effect_table.iloc[k]
        details = {"figure": float(ratio[k]), "threshold": 1.0, "unit": "after/before",
                   "where": f"{row['maneuver']} with {row['set']}"}
    return Finding.judged("correction reduces the error", worse.empty, why, **details,
                          action="" if worse.empty else "do not uplink; review the model and the maneuvers named")


def checks(model: str, calibrations: dict, spec, sampler: dict, diagnostics: dict, comparison: pd.DataFrame,
             effect_table: pd.DataFrame, cfg: dict, prior_conflict: Finding | None = None,
             sensor_class: str | None = None, flown: pd.DataFrame | None = None) -> list:
    """Every check behind the verdict on the reviewed ``model``, in the order of ``verdict.json``.

    ``calibrations`` maps every model to its ``calibration.csv`` (the others' for the
    model-sensitivity check), ``comparison`` is ``model_comparison.csv``, ``effect_table``
    the reviewed model's `estimate_effect`, ``cfg`` the whole config and ``prior_conflict`` the
    reviewed model's `gyrocal.criticism.priorconflict.conflict_check` (after the misfit check);
    ``sensor_class`` the campaign's gyro class (``campaign.yaml``), whose limits bound the estimates;
    ``flown`` the reviewed model's scale factors at the campaign's rates where they change with the rate
    (`gyrocal.criticism.uplinked.uplinked_intervals`), whose intervals the precision check judges.
    """
    calibration, rcfg = calibrations[model], cfg["report"]
    classified = modelchoice.typed(comparison)
    conflict = [] if prior_conflict is None else [prior_conflict]
    return [convergence_check(calibration, spec, sampler, cfg["convergence"]),
            misfit_check(diagnostics, cfg["diagnostics"]["structure_log10_p_min"]),
            *conflict,
            informed_check(spec),
            interval_check(calibration, spec, rcfg, flown),
            bounds_check(calibration, spec, physical_bounds(rcfg, sensor_class)),
            correction_check(effect_table),
            modelchoice.plausibility_check(classified),
            modelchoice.sensitivity_check(classified, calibrations, informed_core(spec),
                                          cfg["model_choice"]["agree_sd"], width_limits(rcfg, spec))]


def verdict(campaign: str, model: str, findings) -> dict:
    """``verdict.json``: GO when every finding passes, else NO-GO, with every check behind it."""
    findings = list(findings)
    return {"campaign": campaign, "model": model, "verdict": "GO" if all(f.passed for f in findings) else "NO-GO",
            "checks": [f.as_check() for f in findings]}
