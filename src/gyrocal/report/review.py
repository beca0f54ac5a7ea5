"""The pre-uplink review: one self-contained HTML file per campaign (docs/interface.md section 7).

A verdict first (GO or NO-GO, with every check and the channel or maneuver that failed
it), then the paper's tables with uncertainty, the model against the measurements per
maneuver, the posterior, what the residuals point to, the correction to uplink with the
attitude error before and after it, and the data accounting a reviewer needs to
reproduce the run.
"""

import base64
import html
import json

import numpy as np
import pandas as pd
import yaml

from gyrocal import __version__
from gyrocal.criticism import modelchoice
from gyrocal.inference import identification, preprocess
from gyrocal.inference.calibration import core_rows, posterior_mean_params
from gyrocal.inference.classic import hold_windows
from gyrocal.io import telemetry
from gyrocal.model.units import AXES, PAPER_AXES, paper_term, rad_to_arcsec
from gyrocal.report import figures as plots

EMBED_PNG = {"dpi": 80, "pil_kwargs": {"compress_level": 3}}  # zlib 3: 28 % faster, 8 % larger
"""How the report's figures are rendered."""


def embed_png(data: bytes) -> str:
    """PNG bytes as an inline ``<img>``, so the report is one self-contained file."""
    return f'<img alt="figure" src="data:image/png;base64,{base64.b64encode(data).decode()}">'


def draw_all(jobs, processes: int = 1) -> list:
    """`embed_png` of each ``(plots function name, its arguments)``, in order, drawn by ``processes``
    processes (`plots.render_all`); the PNG bytes are the same either way."""
    return [embed_png(data) for data in plots.render_all(jobs, processes, **EMBED_PNG)]


def _table(frame: pd.DataFrame, table_id=None, classes="") -> str:
    attrs = f' id="{table_id}"' if table_id else ""
    return frame.to_html(index=False, escape=True, border=0, classes=classes, na_rep="").replace(
        "<table", f"<table{attrs}", 1)


def entry(row, truth=None) -> str:
    """Point, mean and 95 % interval of one parameter, as one table cell."""
    text = f"{row['point']:.1f} | {row['mean']:.1f} [{row['ci95_low']:.1f}, {row['ci95_high']:.1f}]"
    if truth is not None:
        inside = row["ci95_low"] <= truth <= row["ci95_high"]
        text += f" (truth {truth:.0f}{'' if inside else ' OUTSIDE'})"
    return text


def paper_tables(calibration: pd.DataFrame, channels, in_loop, truth=None) -> dict:
    """Tables 1-3 of the paper, each entry point | mean [95 % interval] (truth)."""
    cal = calibration.set_index(["channel", "parameter"])

    def cell(channel, parameter):
        row = cal.loc[(channel, parameter)]
        t = truth.get(channel, {}).get(parameter) if truth else None
        return entry(row, t)

    by_name = {c.name: c for c in channels}
    selected = {by_name[n].axis: by_name[n] for n in in_loop}
    t1 = [{"spacecraft axis": f"{'Positive' if p == 'sf_pos' else 'Negative'} {a.capitalize()} Axis",
           "channel": selected[a].name, "residual scale factor (ppm)": cell(selected[a].name, p)}
          for a in PAPER_AXES for p in ("sf_pos", "sf_neg")]
    t1_mis = []
    for a in PAPER_AXES:
        c = selected[a]
        for b in PAPER_AXES:
            if b != a:
                t1_mis.append({"term": paper_term(a, b), "contract name": f"mis_{b}",
                               "channel": c.name, "misalignment (arcsec)": cell(c.name, f"mis_{b}")})
    t2, t3 = [], []
    for a in PAPER_AXES:
        for c in sorted((c for c in channels if c.axis == a), key=lambda c: (c.dtg or 0, c.name)):
            t2.append({"axis": a, "DTG": "-" if c.dtg is None else f"DTG#{c.dtg}", "channel": c.name,
                       "selected": "yes" if c.name in in_loop else "no",
                       "positive scale factor (ppm)": cell(c.name, "sf_pos"),
                       "negative scale factor (ppm)": cell(c.name, "sf_neg")})
            others = [b for b in PAPER_AXES if b != a]
            row = {"axis": a, "DTG": "-" if c.dtg is None else f"DTG#{c.dtg}", "channel": c.name}
            for b in others:
                row[f"{paper_term(a, b)} = mis_{b} (arcsec)"] = cell(c.name, f"mis_{b}")
            t3.append(row)
    return {"table1_sf": pd.DataFrame(t1), "table1_mis": pd.DataFrame(t1_mis),
            "table2": pd.DataFrame(t2), "table3": pd.DataFrame(t3)}


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


def width_limits(rcfg: dict, spec) -> dict:
    """The widest acceptable 95 % interval of each channel-model unit (``max_ci_width_<unit>``)."""
    return {unit: rcfg[f"max_ci_width_{unit}"] for unit in set(spec.units[spec.core])}


def mounting_text(mounting: dict) -> str:
    """What the reviewer must know of the reference's mounting: where it came from and, when the data
    aligned it, which misalignment combinations the data can then tell apart."""
    if not mounting:
        return "The reference measures the body frame itself (no mounting declared)."
    text = f"Reference mounting {mounting['source']}: {mounting['angle_deg']:.3f} deg from body axes"
    if "sd_deg" in mounting:
        text += " (sd about " + ", ".join(f"{a} {v:.3g} deg" for a, v in mounting["sd_deg"].items()) + ")"
    if mounting["source"] != "nominal (campaign.yaml)":
        text += (". Everything is relative: the alignment from the data takes up the rotation the gyro triad "
                 "shares with the reference, so the misalignments are relative to the reference as the data "
                 "align it. The data tell apart each pair's sum (mis_b of the a channel plus mis_a of the b "
                 "channel: the triad's non-orthogonality), not the triad's rotation as a whole")
    return text + "."


def informed_core(spec) -> list:
    """Labels of the channel-model terms the data inform (prior-only ones have their own check)."""
    return [p.label for p in spec.parameters[spec.core] if not p.prior_only]


def verdict_checks(calibration, spec, sampler, diagnostics, effect_table, rcfg, conv) -> list:
    """The GO/NO-GO checks; each names what failed it and why. The interval and bound
    checks apply to the channel model's terms, with the thresholds of their unit
    (``max_ci_width_<unit>``, ``physical_bound_<unit>`` in the config's ``report:``)."""
    checks = []
    base = core_rows(spec, calibration)
    bad = base[(base["r_hat"] >= conv["r_hat_max"]) | (base["ess_bulk"] < conv["ess_bulk_min"])]
    checks.append(("converged", bad.empty and sampler["converged"],
                   "every parameter has r_hat < {} and bulk ESS >= {}".format(conv["r_hat_max"], conv["ess_bulk_min"])
                   if bad.empty and sampler["converged"] else
                   "not converged: " + (", ".join(f"{r.channel}.{r.parameter} (r_hat {r.r_hat:.3f}, ESS {r.ess_bulk:.0f})"
                                                  for r in bad.itertuples()) or "chains shorter than the autocorrelation limit")))
    failed = [c for c in diagnostics["checks"] if not c["passed"]]
    checks.append(("no misfit", not diagnostics["misfit"],
                   "the residuals are consistent with the noise model" if not failed else
                   "misfit: " + "; ".join(f"{c['check']}: {c['why']}" for c in failed)
                   + f". Best explanation: {diagnostics['ranking'][0]['kind']} {diagnostics['ranking'][0]['name']}"))
    uninformed = [p for p in spec.parameters if p.prior_only]
    channels = sorted({p.owner for p in uninformed if p.core})
    checks.append(("every parameter informed by the data", not uninformed,
                   "every parameter has a maneuver that informs it" if not uninformed else
                   "prior-only (the posterior is the prior): " + "; ".join(
                       f"{p.label} ({p.prior_only})" for p in uninformed)
                   + (f". No correction for {', '.join(channels)}" if channels else "")))
    wide = modelchoice.too_wide(calibration, informed_core(spec), width_limits(rcfg, spec))
    checks.append(("intervals narrow enough", not wide,
                   f"every 95 % interval is narrower than {rcfg['max_ci_width_ppm']} ppm / {rcfg['max_ci_width_arcsec']} arcsec"
                   if not wide else "too wide: " + ", ".join(f"{w['label']} ({w['width']:.1f} {w['unit']})"
                                                             for w in wide)))
    bound = np.array([rcfg[f"physical_bound_{unit}"] for unit in base["unit"]])
    out = base[np.abs(base["mean"].to_numpy()) > bound]
    checks.append(("within physical bounds", out.empty,
                   f"every estimate is within {rcfg['physical_bound_ppm']} ppm / {rcfg['physical_bound_arcsec']} arcsec"
                   if out.empty else "outside: " + ", ".join(f"{r.channel}.{r.parameter} = {r.mean:.0f} {r.unit}"
                                                             for r in out.itertuples())))
    worse = effect_table[effect_table["after norm"] >= effect_table["before norm"]]
    checks.append(("correction reduces the error", worse.empty,
                   "the correction reduces the end-of-maneuver attitude error on every maneuver and channel set"
                   if worse.empty else "not reduced on: " + ", ".join(
                       f"{r['maneuver']} with {r['set']} ({r['before norm']:.1f} -> {r['after norm']:.1f} arcsec)"
                       for r in worse.to_dict("records"))))
    return [{"check": n, "passed": bool(p), "why": w} for n, p, w in checks]


def build_context(model, maneuvers, tables, est, diagnostics, sampler, correction_doc, correction_path, fit, idata,
                  comparison, info, truth, cfg, calibrations, processes: int = 1) -> dict:
    """Everything `render` shows, from what the report step read: the reviewed model's
    files, the campaign's maneuvers and preprocess tables (same order), ``input.json``
    (``info``), the simulation's truth (or None), the whole config and every model's
    ``calibration.csv`` (the reviewed one's, and the others' for the model-sensitivity check).
    Figures are drawn by ``processes`` processes (`draw_all`)."""
    calibration = calibrations[model]
    spec, channels = est.spec, est.spec.channels
    params = [posterior_mean_params(spec, calibration, est.biases[m]) for m in range(len(maneuvers))]
    nominal = [spec.channel_params(np.zeros(len(spec)), est.biases[m]) for m in range(len(maneuvers))]
    effect_table = correction_effect(maneuvers, params, nominal)
    checks = verdict_checks(calibration, spec, sampler, diagnostics, effect_table, cfg["report"], cfg["convergence"])
    classified = comparison.assign(plausible=comparison["plausible"].astype(bool),
                                   loo_rejected=comparison["loo_rejected"].astype(bool),
                                   rejected_by=comparison["rejected_by"].astype("string").fillna(""))
    core_labels = informed_core(spec)
    checks += [modelchoice.plausibility_check(classified),
               modelchoice.sensitivity_check(classified, calibrations, core_labels, cfg["model_choice"]["agree_sd"],
                                             width_limits(cfg["report"], spec))]
    jobs = []
    for data, table in zip(maneuvers, tables):
        own = fit[(fit["maneuver"] == data.id) & (fit["set"] == 0)]
        jobs += [("maneuver_figure", (table, f"{data.id}: model {model}, in-loop set", own)),
                 ("residual_figure", (fit[fit["maneuver"] == data.id], data.id))]
    jobs += [("pair_figure", (idata, c.name)) for c in channels]
    jobs += [("trace_figure", (idata, calibration)), ("comparison_figure", (comparison,))]
    drawn = draw_all(jobs, processes)
    figures = {d.id: drawn[2 * m] + drawn[2 * m + 1] for m, d in enumerate(maneuvers)}
    posterior_figs = "".join(drawn[2 * len(maneuvers):-1])
    draws = idata.posterior["channel_param"].sel(parameter=list(spec.labels)).to_numpy()
    pairs = identification.confounded_pairs(np.cov(draws.reshape(-1, len(spec)).T), spec.free, spec.labels)
    convergence = calibration[["channel", "parameter", "unit", "mean", "sd", "r_hat", "ess_bulk"]].round(
        {"mean": 2, "sd": 2, "r_hat": 4, "ess_bulk": 0})
    accounting = pd.DataFrame([{"maneuver": d.id, **d.counts} for d in maneuvers])
    accounting.loc[len(accounting)] = {"maneuver": "campaign files", "st_read": info["rows"]["star_tracker"],
                                       "st_invalid": info["rows"]["star_tracker_invalid"],
                                       "st_outliers": info["rows"]["star_tracker_outliers"],
                                       "gyro_read": info["rows"]["gyro"]}
    return {
        "campaign": info["campaign"], "model": model, "effects": list(spec.effect_names), "checks": checks,
        "simulated": truth is not None,
        "tables": paper_tables(calibration, channels, maneuvers[0].sets[0], truth),
        "maneuver_figures": figures, "posterior_figures": posterior_figs, "convergence": convergence,
        "confounded": pd.DataFrame(pairs, columns=["parameter", "with", "posterior correlation"]).round(3),
        "diagnostics": diagnostics, "comparison": comparison.round(3),
        "comparison_figure": drawn[-1],
        "correction": correction_doc, "correction_path": str(correction_path),
        "effect_table": effect_table.drop(columns=["before norm", "after norm"]).assign(
            **{"before norm (arcsec)": effect_table["before norm"].round(1),
               "after norm (arcsec)": effect_table["after norm"].round(1)}),
        "accounting": accounting, "warnings": info["warnings"],
        "outliers": pd.DataFrame(info["star_tracker_outliers"],
                                 columns=["maneuver", "time_s", "line", "size_arcsec", "mahalanobis", "kind"]
                                 ).fillna({"kind": "outlier"}).round(2),
        "renormalised": info["rows"]["star_tracker_renormalised"], "mounting": mounting_text(info["mounting"]),
        "checksums": info["checksums_sha256"], "sampler": sampler,
        "config": yaml.safe_dump(cfg, sort_keys=False),
    }


CSS = """
body{font-family:system-ui,Arial,sans-serif;margin:24px;max-width:1400px;color:#222}
h1{margin-bottom:4px} h2{border-bottom:2px solid #ccc;padding-bottom:4px;margin-top:36px}
table{border-collapse:collapse;margin:8px 0;font-size:13px} td,th{border:1px solid #ccc;padding:3px 7px;text-align:left}
th{background:#f0f0f0} .verdict{font-size:40px;font-weight:bold;padding:16px 24px;color:#fff;border-radius:6px}
.go{background:#1e7d32} .nogo{background:#c62828} .fail{color:#c62828;font-weight:bold} .pass{color:#1e7d32}
img{max-width:100%} .small{font-size:12px;color:#555} pre{background:#f6f6f6;padding:8px;font-size:12px;overflow-x:auto}
"""


def verdict(ctx: dict) -> dict:
    """The verdict and the checks behind it, as ``verdict.json`` holds them."""
    go = all(c["passed"] for c in ctx["checks"])
    return {"campaign": ctx["campaign"], "model": ctx["model"], "verdict": "GO" if go else "NO-GO",
            "checks": ctx["checks"]}


def render(ctx: dict) -> str:
    """The HTML document from the assembled context (all figures already embedded)."""
    go = verdict(ctx)["verdict"] == "GO"
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>gyrocal review: {html.escape(ctx['campaign'])}</title>",
             f"<style>{CSS}</style></head><body>",
             f"<h1>Gyro calibration review: {html.escape(ctx['campaign'])}</h1>",
             f"<p class='small'>gyrocal {__version__}; model reviewed: <b>{html.escape(ctx['model'])}</b> "
             f"({html.escape(', '.join(ctx['effects']))})</p>",
             f"<div id='verdict' class='verdict {'go' if go else 'nogo'}'>{'GO' if go else 'NO-GO'}</div>",
             "<h2>Checks behind the verdict</h2>"]
    rows = "".join(f"<tr><td>{html.escape(c['check'])}</td><td class='{'pass' if c['passed'] else 'fail'}'>"
                   f"{'pass' if c['passed'] else 'FAIL'}</td><td>{html.escape(c['why'])}</td></tr>" for c in ctx["checks"])
    parts.append(f"<table id='checks'><tr><th>check</th><th>result</th><th>detail</th></tr>{rows}</table>")
    parts.append("<h2>The paper's tables, with uncertainty</h2><p class='small'>Each entry: WLS point estimate | "
                 "posterior mean [central 95 % interval]" + (" (true value of the simulation)" if ctx["simulated"] else "")
                 + ". Axes numbered as in the paper: 1 = yaw, 2 = roll, 3 = pitch; mc_ij is channel i toward axis j.</p>")
    t = ctx["tables"]
    parts += ["<h3>Table 1. Residual scale factors and misalignments, selected channels</h3>",
              _table(t["table1_sf"], "table1"), _table(t["table1_mis"], "table1-mis"),
              "<h3>Table 2. Residual scale factors, all DTG channels</h3>", _table(t["table2"], "table2"),
              "<h3>Table 3. Residual misalignments, all DTG channels</h3>", _table(t["table3"], "table3")]
    parts.append("<h2>The model against the measurements</h2><p class='small'>Per maneuver, as in the paper's "
                 "Figures 1-3: the rate profile, then the error of the star tracker relative to the gyro attitude with "
                 "nominal parameters, the model's posterior prediction with its 95 % band, and crosses where the "
                 "measurement falls outside the band. Below each, the residuals.</p>")
    for m, figs in ctx["maneuver_figures"].items():
        parts.append(f"<h3>{html.escape(m)}</h3>{figs}")
    parts.append("<h2>The posterior</h2>")
    parts.append(_table(ctx["convergence"], "convergence"))
    parts.append("<h3>Pairs the data cannot separate</h3><p class='small'>Parameters whose posterior correlation "
                 f"exceeds {identification.CORRELATION_MAX} in magnitude: the maneuvers pin down their combination, "
                 "not each; their intervals are as wide as that confounding.</p>")
    parts.append(_table(ctx["confounded"], "confounded") if len(ctx["confounded"]) else
                 "<p id='confounded'>None: every pair is told apart.</p>")
    parts.append(ctx["posterior_figures"])
    parts.append("<h2>What the residuals point to</h2>")
    parts.append(f"<p>Misfit: <b class='{'fail' if ctx['diagnostics']['misfit'] else 'pass'}'>"
                 f"{ctx['diagnostics']['misfit']}</b>; residual RMS {ctx['diagnostics']['residual_rms_arcsec']:.2f} arcsec, "
                 f"the stated noise predicts {ctx['diagnostics']['noise_rms_arcsec']:.2f} arcsec.</p>")
    parts.append(_table(pd.DataFrame(ctx["diagnostics"]["checks"]), "misfit-checks"))
    parts.append("<h3>Ranking: what most likely explains the misfit</h3>")
    parts.append(_table(pd.DataFrame(ctx["diagnostics"]["ranking"])[["name", "kind", "score", "chi2_drop", "df",
                                                                      "log10_p", "description"]], "ranking"))
    parts.append("<h3>Model comparison</h3><p class='small'>The reviewed model is the plausible variant (no misfit, "
                 "and not more than model_choice.reject_se paired se below the best by exact leave-one-maneuver-out "
                 "elpd) with the best elpd_lomo. Every variant LOO does not reject must agree with the others on each "
                 "scale factor and misalignment within model_choice.agree_sd combined sd, and know each within the "
                 "interval limits; otherwise the verdict is NO-GO.</p>")
    parts.append(_table(ctx["comparison"], "comparison"))
    parts.append(ctx["comparison_figure"])
    parts.append("<h2>The correction to uplink</h2><p class='small'>Exactly as written to "
                 f"<code>{html.escape(ctx['correction_path'])}</code>. {html.escape(ctx['correction']['convention'])}</p>")
    for s in ctx["correction"]["sets"]:
        parts.append(f"<h3>{'In-loop' if s['in_loop'] else 'Redundant'} set: {html.escape(', '.join(s['channels']))}</h3>")
        for key in ("matrix_pos", "matrix_neg", "misalignment_correction"):
            frame = pd.DataFrame(s[key], columns=s["channels"], index=s["axes"]).map(lambda v: f"{v:.9f}")
            parts.append(f"<p class='small'>{key}</p>" + frame.to_html(border=0))
        parts.append("<p class='small'>scale_correction_pos: " + ", ".join(f"{v:.9f}" for v in s["scale_correction_pos"])
                     + "; scale_correction_neg: " + ", ".join(f"{v:.9f}" for v in s["scale_correction_neg"]) + "</p>")
    parts.append("<h3>Attitude error at the end of every maneuver, before and after the correction</h3>")
    parts.append(_table(ctx["effect_table"].round(1), "before-after"))
    parts.append("<h2>Data accounting</h2>")
    parts.append(f"<p id='mounting'>{html.escape(ctx['mounting'])}</p>")
    parts.append(_table(ctx["accounting"], "accounting"))
    parts.append(f"<h3>Star-tracker outliers left out of the fit ({len(ctx['outliers'])})</h3><p class='small'>"
                 "Samples whose departure from their neighbours the motion cannot explain, beyond what the data's "
                 "own noise allows (kind outlier), or that leave the trend of the error between the sensors and "
                 "come back within a few seconds (kind excursion: a glitch of the reference, since a gyro's error "
                 "integrates and cannot come back); line is the line of star_tracker.csv "
                 "(gyrocal.checks).</p>")
    parts.append(_table(ctx["outliers"], "outliers"))
    parts.append(f"<h3>Warnings from validation ({len(ctx['warnings'])})</h3>")
    parts.append("<ul id='warnings'>" + "".join(f"<li>{html.escape(w)}</li>" for w in ctx["warnings"]) + "</ul>")
    parts.append(f"<p class='small'>Star-tracker quaternions renormalised (written norm off 1 by more than "
                 f"{telemetry.UNIT_NORM_TOL:g}): {ctx['renormalised']}.</p>")
    parts.append(f"<p>Input files (SHA-256):</p><pre>{html.escape(json.dumps(ctx['checksums'], indent=1))}</pre>")
    parts.append(f"<p>Sampler: seed {ctx['sampler']['seed']}, {ctx['sampler']['ensembles']} ensembles x "
                 f"{ctx['sampler']['walkers']} walkers, {ctx['sampler']['steps']} steps after {ctx['sampler']['burn_steps']} "
                 f"burn-in, longest autocorrelation {ctx['sampler']['tau_max_steps']:.1f} steps, acceptance "
                 f"{np.mean(ctx['sampler']['acceptance']):.2f}.</p>")
    parts.append(f"<p>Configuration:</p><pre>{html.escape(ctx['config'])}</pre></body></html>")
    return "".join(parts)
