"""The pre-uplink review: one self-contained HTML file per campaign (docs/interface.md section 7).

A verdict first (GO or NO-GO, with every check and the channel or maneuver that failed
it), then the paper's tables with uncertainty, the model against the measurements per
maneuver, the posterior, what the residuals point to, the correction to uplink with the
attitude error before and after it, and the data accounting a reviewer needs to
reproduce the run. The page is ``templates/review.html.j2`` over a `ReviewContext`; the
verdict and its findings come from `gyrocal.criticism.verdict`, and nothing here decides.
"""

import base64
import json
from pathlib import Path

import jinja2
import numpy as np
import pandas as pd
import yaml
from markupsafe import Markup

from gyrocal import __version__
from gyrocal.criticism import modelchoice
from gyrocal.criticism import verdict as judge
from gyrocal.criticism.uplinked import at_uplink
from gyrocal.inference.fit import identification
from gyrocal.io import telemetry
from gyrocal.model import combinations
from gyrocal.model.units import PAPER_AXES, paper_term
from gyrocal.report import figures as plots
from gyrocal.report import noisemodel, resolution
from gyrocal.report.context import CorrectionSet, ReviewContext, ReviewInputs, campaign_words

__all__ = [
    "COMBINATION_HEADINGS", "EMBED_PNG", "NOT_DRAWN", "ORTHOGONALITY_SHOWN", "ReviewContext", "ReviewInputs",
    "build_context", "channel_kind", "draw_all", "embed_png", "entry", "fold", "html_table", "mounting_text", "number",
    "paper_tables", "render"
]

EMBED_PNG = {"dpi": 80, "pil_kwargs": {"compress_level": 3}}  # zlib 3: 28 % faster, 8 % larger
"""How the report's figures are rendered."""


def embed_png(data: bytes) -> str:
    """PNG bytes as an inline ``<img>``, so the report is one self-contained file."""
    return f'<img alt="figure" src="data:image/png;base64,{base64.b64encode(data).decode()}">'


NOT_DRAWN = '<p class="not-drawn">Figure not drawn (the config\'s <code>report.figures: false</code>).</p>'
"""What stands in a figure's place where the config asks for none."""


def draw_all(jobs, processes: int = 1, figures: bool = True) -> list:
    """`embed_png` of each ``(plots function name, its arguments)``, in order, drawn by ``processes``
    processes (`plots.render_all`); the PNG bytes are the same either way. ``figures`` False: none is
    drawn (half of a short campaign's report step), `NOT_DRAWN` stands in each one's place."""
    if not figures:
        return [NOT_DRAWN] * len(jobs)
    return [embed_png(data) for data in plots.render_all(jobs, processes, **EMBED_PNG)]


def html_table(frame: pd.DataFrame, table_id=None, index: bool = False) -> Markup:
    """A table as HTML (its cells escaped), with ``id="table_id"``: the template's ``table`` filter."""
    attrs = f' id="{table_id}"' if table_id else ""
    return Markup(frame.to_html(index=index, escape=True, border=0, na_rep="").replace("<table", f"<table{attrs}", 1))


def entry(row, truth=None) -> str:
    """Point, mean and 95 % interval of one parameter, as one table cell."""
    text = f"{row['point']:.1f} | {row['mean']:.1f} [{row['ci95_low']:.1f}, {row['ci95_high']:.1f}]"
    if truth is not None:
        inside = row["ci95_low"] <= truth <= row["ci95_high"]
        text += f" (truth {truth:.0f}{'' if inside else ' OUTSIDE'})"
    return text


ORTHOGONALITY_SHOWN = ("set", "channels", "parameter", "definition", "mean", "sd", "ci95_low", "ci95_high", "prior_only")
"""The columns of ``orthogonality.csv`` the review shows (arcsec)."""

COMBINATION_HEADINGS = {"sf_mean": "sf_mean = (sf_pos + sf_neg) / 2 (ppm)", "sf_asym": "sf_asym = sf_pos - sf_neg (ppm)"}
"""Table 2's columns of each channel's identifiable combinations (`gyrocal.model.combinations`)."""


def paper_tables(calibration: pd.DataFrame, channels, in_loop, truth=None, axis_heading: str = "spacecraft axis") -> dict:
    """Tables 1-3 of the paper, each entry point | mean [95 % interval] (truth); table 2 also shows each
    channel's identifiable combinations. A column names each channel's DTG only where the campaign
    declares DTGs (campaign.yaml's ``dtg:``). ``axis_heading``: table 1's axis column (a lab's
    ``body axis``, `campaign_words`)."""
    cal = calibration.set_index(["channel", "parameter"])
    if truth:
        truth = {name: {**values, **combinations.combination_values(values)} for name, values in truth.items()}

    def cell(channel, parameter):
        """A symmetric model's one ``sf`` fills both branches' cells (each against its branch's truth)."""
        row = cal.loc[(channel, parameter if (channel, parameter) in cal.index else "sf")]
        t = truth.get(channel, {}).get(parameter) if truth else None
        return entry(row, t)

    by_name = {c.name: c for c in channels}
    selected = {by_name[n].axis: by_name[n] for n in in_loop}
    t1 = [{axis_heading: f"{'Positive' if p == 'sf_pos' else 'Negative'} {a.capitalize()} Axis",
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
    gyro = {"DTG": lambda c: "-" if c.dtg is None else f"DTG#{c.dtg}"} if any(c.dtg for c in channels) else {}
    for a in PAPER_AXES:
        for c in sorted((c for c in channels if c.axis == a), key=lambda c: (c.dtg or 0, c.name)):
            t2.append({"axis": a, **{k: f(c) for k, f in gyro.items()}, "channel": c.name,
                       "selected": "yes" if c.name in in_loop else "no",
                       "positive scale factor (ppm)": cell(c.name, "sf_pos"),
                       "negative scale factor (ppm)": cell(c.name, "sf_neg"),
                       **{heading: cell(c.name, name) for name, heading in COMBINATION_HEADINGS.items()
                          if (c.name, name) in cal.index}})
            others = [b for b in PAPER_AXES if b != a]
            row = {"axis": a, **{k: f(c) for k, f in gyro.items()}, "channel": c.name}
            for b in others:
                row[f"{paper_term(a, b)} = mis_{b} (arcsec)"] = cell(c.name, f"mis_{b}")
            t3.append(row)
    return {"table1_sf": pd.DataFrame(t1), "table1_mis": pd.DataFrame(t1_mis),
            "table2": pd.DataFrame(t2), "table3": pd.DataFrame(t3)}


def channel_kind(channels) -> str:
    """What the report calls the channels: ``DTG`` where campaign.yaml gives every one a ``dtg:``
    number, else ``gyro`` (a MEMS triad is not a DTG)."""
    return "DTG" if all(c.dtg is not None for c in channels) else "gyro"


def _sentence(text: str) -> str:
    return text[:1].upper() + text[1:] + ("" if text.endswith(".") else ".")


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


def _correction_sets(correction: dict) -> list:
    """Each channel set of ``correction.json`` with its matrices as 9-decimal tables."""
    return [CorrectionSet(
        in_loop=s["in_loop"], channels=s["channels"],
        matrices={key: pd.DataFrame(s[key], columns=s["channels"], index=s["axes"]).map(lambda v: f"{v:.9f}")
                  for key in ("matrix_pos", "matrix_neg", "misalignment_correction")},
        scale_correction_pos=", ".join(f"{v:.9f}" for v in s["scale_correction_pos"]),
        scale_correction_neg=", ".join(f"{v:.9f}" for v in s["scale_correction_neg"])) for s in correction["sets"]]


def build_context(inputs: ReviewInputs, processes: int = 1) -> ReviewContext:
    """Everything the template shows, from what the report step read and the verdict's findings.
    Figures are drawn by ``processes`` processes (`draw_all`), unless the config's ``report.figures``
    is false."""
    spec, calibration, maneuvers, info = inputs.spec, inputs.calibration, inputs.maneuvers, inputs.info
    words = campaign_words(maneuvers)
    jobs = []
    for data, table in zip(maneuvers, inputs.tables):
        own = inputs.fit[(inputs.fit["maneuver"] == data.id) & (inputs.fit["set"] == 0)]
        jobs += [("maneuver_figure", (table, f"{data.id}: model {inputs.model}, {words['first_set_figure']}", own,
                                      words["kind"] == "flight")),
                 ("residual_figure", (inputs.fit[inputs.fit["maneuver"] == data.id], data.id))]
    jobs += [("pair_figure", (inputs.posterior, c.name)) for c in spec.channels]
    jobs += [("trace_figure", (inputs.posterior, calibration)), ("comparison_figure", (inputs.comparison,))]
    drawn = [Markup(img) for img in draw_all(jobs, processes, inputs.config["report"].get("figures", True))]
    draws = inputs.posterior.posterior["channel_param"].sel(parameter=list(spec.labels)).to_numpy()
    cov = np.cov(draws.reshape(-1, len(spec)).T)
    pairs = identification.confounded_pairs(cov, spec.free, spec.labels)
    resolved = resolution.resolution_table(spec, at_uplink(calibration, inputs.flown),
                                           judge.width_limits(inputs.config["report"], spec))
    accounting = pd.DataFrame([{"maneuver": d.id, **d.counts} for d in maneuvers])
    accounting.loc[len(accounting)] = {"maneuver": "campaign files", "st_read": info["rows"]["star_tracker"],
                                       "st_invalid": info["rows"]["star_tracker_invalid"],
                                       "st_outliers": info["rows"]["star_tracker_outliers"],
                                       "gyro_read": info["rows"]["gyro"]}
    effect = inputs.effect_table
    diagnostics = inputs.diagnostics
    return ReviewContext(
        campaign=info["campaign"], model=inputs.model, effects=list(spec.effect_names), version=__version__,
        verdict=judge.verdict(info["campaign"], inputs.model, inputs.findings)["verdict"],
        findings=list(inputs.findings), simulated=inputs.truth is not None,
        tables=paper_tables(calibration, spec.channels, maneuvers[0].sets[0], inputs.truth, words["axis"]),
        maneuver_figures={d.id: drawn[2 * m] + drawn[2 * m + 1] for m, d in enumerate(maneuvers)},
        posterior_figures=Markup("").join(drawn[2 * len(maneuvers):-1]),
        convergence=calibration[["channel", "parameter", "unit", "mean", "sd", "r_hat", "ess_bulk"]].round(
            {"mean": 2, "sd": 2, "r_hat": 4, "ess_bulk": 0}),
        confounded=pd.DataFrame(pairs, columns=["parameter", "with", "posterior correlation"]).round(3),
        resolution=resolved.round({"mean": 1, "sd": 1, "ci95_low": 1, "ci95_high": 1, "prior_sd": 1, "sd_over_prior": 3,
                                   "ci95_width": 1}),
        resolution_sentences=resolution.channel_sentences(spec, resolved, maneuvers),
        resolution_uplinked=inputs.flown is not None,
        resolved_ratio_max=combinations.RESOLVED_RATIO_MAX, prior_directions=resolution.prior_directions(spec, cov),
        mounting_separability=resolution.mounting_table(spec, cov, info["mounting"]),
        orthogonality=inputs.orthogonality[[c for c in ORTHOGONALITY_SHOWN if c in inputs.orthogonality]].round(
            {"mean": 1, "sd": 1, "ci95_low": 1, "ci95_high": 1}),
        correlation_max=identification.CORRELATION_MAX,
        diagnostics=diagnostics, noise=noisemodel.noise_table(diagnostics).map(_significant),
        noise_clock=noisemodel.clock_sentence(diagnostics, maneuvers[0].gm_clock_s_per_rad, inputs.gm_clock),
        misfit_checks=pd.DataFrame(diagnostics["checks"]),
        ranking=pd.DataFrame(diagnostics["ranking"])[["name", "kind", "score", "chi2_drop", "df", "log10_p",
                                                      "description"]],
        comparison=inputs.comparison.round(3), comparison_figure=drawn[-1],
        convention=inputs.correction["convention"], correction_path=str(inputs.correction_path),
        correction_sets=_correction_sets(inputs.correction),
        effect_table=effect.drop(columns=["before norm", "after norm"]).rename(
            columns={} if words["kind"] == "flight" else {"in loop": "first set"}).assign(
            **{"before norm (arcsec)": effect["before norm"].round(1),
               "after norm (arcsec)": effect["after norm"].round(1)}).round(1),
        mounting=mounting_text(info["mounting"]),
        reference_interval=_sentence((inputs.reference_interval or {}).get("reason", "not recorded (a run before "
                                                                                   "gyrocal recorded it)")),
        accounting=accounting,
        outliers=pd.DataFrame(info["star_tracker_outliers"],
                              columns=["maneuver", "time_s", "line", "size_arcsec", "mahalanobis", "kind"]
                              ).fillna({"kind": "outlier"}).round(2),
        warnings=list(info["warnings"]), renormalised=info["rows"]["star_tracker_renormalised"],
        unit_norm_tol=telemetry.UNIT_NORM_TOL, checksums=json.dumps(info["checksums_sha256"], indent=1),
        sampler=inputs.sampler, acceptance=float(np.mean(inputs.sampler["acceptance"])),
        config=yaml.safe_dump(inputs.config, sort_keys=False),
        channel_kind=channel_kind(spec.channels),
        reviewed_why=modelchoice.reviewed_reason(modelchoice.typed(inputs.comparison)),
        refused=pd.DataFrame(inputs.refused, columns=["model", "status", "step", "reason"]), words=words,
        loop=inputs.loop, loop_steps=list(inputs.loop_steps), disagreement=inputs.disagreement)


FOLD_CHARS = 200
"""A check's detail shown in full up to this many characters (about three lines of the checks table's
detail column, at least 420 px wide); the rest folds into ``<details>`` (`fold`)."""


def fold(text: str, limit: int = FOLD_CHARS) -> Markup:
    """A finding's detail, at most ``limit`` characters shown, cut after the last sentence or clause that
    fits (else at a space), the rest folded into ``<details>``: the template's ``fold`` filter."""
    text = str(text)
    if len(text) <= limit:
        return Markup.escape(text)
    head = text[:limit]
    cut = max(head.rfind(". "), head.rfind("; "))
    cut = cut + 1 if cut > limit // 3 else (head.rfind(" ") if head.rfind(" ") > 0 else limit)
    return (Markup.escape(text[:cut].rstrip()) + Markup(" <details class='more'><summary>more</summary>")
            + Markup.escape(text[cut:].strip()) + Markup("</details>"))


def _significant(value):
    """A table cell: a number to four significant digits (blank where there is none), anything else as it is."""
    if isinstance(value, str):
        return value
    return f"{value:.4g}" if np.isfinite(value) else ""


def number(value) -> str:
    """A finding's figure or threshold as the report prints it: five significant digits."""
    return f"{value:.5g}"


TEMPLATES = jinja2.Environment(loader=jinja2.FileSystemLoader(Path(__file__).parent / "templates"),
                               autoescape=True, undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=True)
"""The report's templates, autoescaped: every text from the data is escaped unless it is `Markup`."""
TEMPLATES.filters.update(table=html_table, number=number, fold=fold)


def render(ctx: ReviewContext) -> str:
    """The HTML document of ``templates/review.html.j2`` over the context (all figures already embedded)."""
    return TEMPLATES.get_template("review.html.j2").render(ctx=ctx)
