"""Which model the review rests on, and whether the answer hangs on that choice.

The rule (docs/usage.md, "Which model is reviewed"):

1. A variant is *rejected* when its residuals misfit the noise model, or when LOO rejects
   it: its exact leave-one-maneuver-out elpd falls more than ``reject_se`` paired standard
   errors (of at least one nat) below the best variant's; or it misfits and its PSIS-LOO
   elpd over 60-s blocks falls that far below the best by that measure. A maneuver left
   out shows a smooth effect that a block's neighbours would interpolate, but six
   maneuvers give a rough standard error; hundreds of blocks give a sharp one, so sharp
   that the few nats a variant loses for parameters the data cannot inform (its prior
   volume) look significant. Rejecting a variant that fits for that would hide the very
   model uncertainty the review must show, so the blocks only confirm a misfit.
2. The variants left are *plausible*; the one with the best elpd is reviewed. With none
   left, the best elpd is reviewed and the verdict is NO-GO.
3. The answer must not hang on the model. Every variant LOO does not reject (a misfitting
   one too: a misfit in a variant that predicts as well says the others lack something)
   must agree with the others, each channel-model term within ``agree_sd`` combined
   standard deviations, and must know every term within the report's interval limits.
   Otherwise the verdict is NO-GO, naming the models, the terms and what would separate
   them. A model the data cannot rule out, under which the correction is unknown or
   different, leaves the correction unknown or different.
"""

import numpy as np
import pandas as pd
from scipy.optimize import minimize
from scipy.special import logsumexp, softmax

from gyrocal.finding import Finding

__all__ = [
    "MEASURES", "SEPARATED_BY", "branch_labels", "branch_rows", "classify", "disagreement_table", "disagreements",
    "interval_widths", "paired_se", "plausibility_check", "reviewed_model", "reviewed_reason", "sensitivity_check",
    "separating_advice", "stacking_weights", "too_wide", "typed"
]

SEPARATED_BY = {
    "scale_factor": ("more and longer rotations each way about each axis (what sets the scale factors per "
                     "direction apart from one symmetric scale factor)"),
    "bias_drift": "longer inertial holds before and after each rotation (a drift bends the held error)",
    "sf_nonlinearity": "a second rotation rate in each direction (the scale factor then differs by rate)",
    "st_latency": "shorter, sharper ramps (a time-tag offset shows where the rate changes)",
    "st_correlated_noise": "a long inertial hold without rotation (the noise's correlation shows at rest)",
}
"""For each library effect, the change to the maneuver plan that shows it apart."""


def paired_se(diff) -> float:
    """Standard error of a sum of pointwise differences (Vehtari et al. 2017, eq. 24)."""
    diff = np.asarray(diff, dtype=float)
    return float(np.sqrt(len(diff) * np.var(diff)))


def stacking_weights(pointwise: np.ndarray) -> np.ndarray:
    """Stacking weights (Yao et al. 2018) of models from their pointwise log predictive
    densities, (n_models, n_points): the mixture maximising the summed log score."""
    pointwise = np.asarray(pointwise, dtype=float)

    def negative_score(z):
        return -np.sum(logsumexp(pointwise + np.log(softmax(np.append(z, 0.0)))[:, None], axis=0))

    z = minimize(negative_score, np.zeros(len(pointwise) - 1), method="BFGS").x
    return softmax(np.append(z, 0.0))


MEASURES = {"lomo_pointwise": ("leave-one-maneuver-out", False), "loo_pointwise": ("block PSIS-LOO", True)}
"""The pointwise columns `classify` compares: how a reason names each, and whether it may
reject only a variant that misfits (rule 1)."""


def classify(table: pd.DataFrame, reject_se: float) -> pd.DataFrame:
    """The comparison table with ``loo_rejected``, ``rejected_by`` ("" when plausible) and
    ``plausible``.

    ``table`` holds ``misfit`` and, per variant, the pointwise values of each measure of
    `MEASURES` present (an array per row); each variant is compared with the best by the
    sum of the measure, using the paired standard error of the pointwise difference.
    """
    out = table.copy()
    reasons, loo_rejected = [], []
    for i, row in out.iterrows():
        why = ["misfit"] if bool(row["misfit"]) else []
        rejected = False
        for column, (name, needs_misfit) in MEASURES.items():
            if column not in out or (needs_misfit and not bool(row["misfit"])):
                continue
            sums = out[column].apply(np.sum)
            best = sums.idxmax()
            diff = np.asarray(row[column]) - np.asarray(out.loc[best, column])
            se = max(paired_se(diff), 1.0)
            if i != best and diff.sum() < -reject_se * se:
                rejected = True
                why.append(f"{name}: elpd {diff.sum():.1f} below {out.loc[best, 'model']} ({-diff.sum() / se:.1f} se)")
        loo_rejected.append(rejected)
        reasons.append("; ".join(why))
    out["loo_rejected"] = loo_rejected
    out["rejected_by"] = reasons
    out["plausible"] = out["rejected_by"] == ""
    return out


def reviewed_model(classified: pd.DataFrame) -> str:
    """The plausible variant with the best elpd; the best elpd of all when none is plausible."""
    pool = classified[classified["plausible"]]
    pool = pool if len(pool) else classified
    return str(pool.loc[pool["elpd_lomo"].idxmax(), "model"])


def disagreements(calibrations: dict, core_labels: list, agree_sd: float) -> list:
    """Channel-model terms on which two variants disagree beyond their intervals.

    ``calibrations`` maps each model to its ``calibration.csv``. Returns dicts (models,
    label, difference, unit, z), largest ``z`` first.
    """
    tables = {m: t.assign(label=t["channel"] + "." + t["parameter"]).set_index("label")
              for m, t in calibrations.items()}
    models = list(tables)
    out = []
    for i, a in enumerate(models):
        for b in models[i + 1:]:
            ta, tb = tables[a].loc[core_labels], tables[b].loc[core_labels]
            diff = (tb["mean"] - ta["mean"]).to_numpy()
            z = np.abs(diff) / np.sqrt(ta["sd"].to_numpy() ** 2 + tb["sd"].to_numpy() ** 2)
            for k in np.flatnonzero(z > agree_sd):
                out.append({"models": (a, b), "label": core_labels[k], "difference": float(diff[k]),
                            "unit": ta["unit"].iloc[k], "z": float(z[k])})
    return sorted(out, key=lambda d: -d["z"])


def separating_advice(effects_a, effects_b) -> str:
    """What would tell two variants apart: the plan change for each effect one has and the
    other lacks (for a plugin's effect, maneuvers that excite it)."""
    differing = sorted(set(effects_a) ^ set(effects_b))
    if {"scale_factor", "scale_factor_symmetric"} <= set(differing):  # one question: are the directions' apart?
        differing.remove("scale_factor_symmetric")
    advice = [f"{e}: {SEPARATED_BY.get(e, 'maneuvers that excite ' + e)}" for e in differing]
    return "; ".join(advice) or "the variants hold the same effects"


def interval_widths(calibration: pd.DataFrame, core_labels: list, width_limits: dict) -> list:
    """Each channel-model term's 95 % interval width (label, width, unit, limit), the limit that of its unit."""
    table = calibration.assign(label=calibration["channel"] + "." + calibration["parameter"]).set_index("label")
    table = table.loc[core_labels]
    width = table["ci95_high"] - table["ci95_low"]
    limit = np.array([width_limits[u] for u in table["unit"]])
    return [{"label": label, "width": float(w), "unit": u, "limit": float(lim)}
            for label, w, u, lim in zip(core_labels, width, table["unit"], limit)]


def too_wide(calibration: pd.DataFrame, core_labels: list, width_limits: dict) -> list:
    """Channel-model terms whose 95 % interval is wider than the limit of their unit."""
    return [w for w in interval_widths(calibration, core_labels, width_limits) if w["width"] > w["limit"]]


def branch_rows(calibration: pd.DataFrame) -> pd.DataFrame:
    """A calibration table with a symmetric model's ``sf`` rows also as ``sf_pos`` and ``sf_neg``
    (the branches it sets equal), so that it compares term by term with a per-direction model's."""
    sym = calibration[calibration["parameter"] == "sf"]
    if sym.empty:
        return calibration
    return pd.concat([calibration] + [sym.assign(parameter=b) for b in ("sf_pos", "sf_neg")], ignore_index=True)


def branch_labels(labels) -> list:
    """Channel-model labels with each symmetric ``<channel>.sf`` as its two branches (`branch_rows`)."""
    return [x for label in labels for x in ([label[:-2] + "sf_pos", label[:-2] + "sf_neg"]
                                             if label.endswith(".sf") else [label])]


def reviewed_reason(classified: pd.DataFrame) -> str:
    """Why the rule reviews the variant it does (`reviewed_model`), in one sentence; the variants' elpd
    are the comparison table's."""
    reviewed = reviewed_model(classified)
    plausible = list(classified.loc[classified["plausible"], "model"])
    if not plausible:
        return (f"{reviewed} is reviewed, though no variant is plausible: it predicts the left-out maneuvers best "
                f"of the {len(classified)} compared")
    if len(plausible) == 1:
        return (f"{reviewed} is reviewed: the only plausible variant of the {len(classified)} compared "
                "(no misfit, not rejected by leave-one-maneuver-out)")
    return (f"{reviewed} is reviewed: of the plausible variants ({', '.join(plausible)}), it predicts the "
            "left-out maneuvers best")


def typed(comparison: pd.DataFrame) -> pd.DataFrame:
    """``model_comparison.csv`` as read back, with `classify`'s columns in their types again."""
    return comparison.assign(plausible=comparison["plausible"].astype(bool),
                             loo_rejected=comparison["loo_rejected"].astype(bool),
                             rejected_by=comparison["rejected_by"].astype("string").fillna(""))


def _model_disagreement(classified: pd.DataFrame, calibrations: dict, core_labels: list, agree_sd: float,
                        width_limits: dict):
    """What the sensitivity check judges: the variants LOO does not reject, every disagreement between
    them (largest first), those beyond ``agree_sd``, and the intervals too wide under a variant not
    reviewed (by variant)."""
    reviewed = reviewed_model(classified)
    members = list(classified.loc[~classified["loo_rejected"].astype(bool), "model"])
    calibrations = {m: branch_rows(t) for m, t in calibrations.items()}
    core_labels = branch_labels(core_labels)
    every = disagreements({m: calibrations[m] for m in members}, core_labels, 0.0)
    found = [d for d in every if d["z"] > agree_sd]
    wide = {m: too_wide(calibrations[m], core_labels, width_limits) for m in members if m != reviewed}
    return reviewed, members, every, found, {m: w for m, w in wide.items() if w}


def _by_unit(widths: list) -> list:
    """Terms too wide under one variant, grouped by unit (ppm, arcsec), in their order."""
    units = list(dict.fromkeys(x["unit"] for x in widths))
    return [(u, [x for x in widths if x["unit"] == u]) for u in units]


def _terms(group: list, shown: int = 3) -> str:
    """A group of terms in a table cell: every label where few, else their count and the first few."""
    labels = [x["label"] for x in group]
    return ", ".join(labels) if len(labels) <= shown else f"{len(labels)} terms: {', '.join(labels[:shown])}, ..."


def _span(values: list) -> str:
    """A width, or the range of several, as the table prints them."""
    lo, hi = min(values), max(values)
    return f"{lo:,.0f}" if round(lo) == round(hi) else f"{lo:,.0f}-{hi:,.0f}"


def _known_within(other: str, group: list) -> str:
    """How loosely the terms of one unit are known under variant ``other``, against their limit."""
    return (f"under {other} known only within {_span([x['width'] for x in group])} {group[0]['unit']} "
            f"(95 %; limit {group[0]['limit']:g})")


def disagreement_table(classified: pd.DataFrame, calibrations: dict, core_labels: list, agree_sd: float,
                       width_limits: dict) -> pd.DataFrame:
    """The sensitivity check's detail as a table, a row per pair of variants and term: the models,
    the term, the difference (its size, and in combined sd), and what would separate the two
    (`separating_advice`), each distinct advice once, on its first row. Terms known too loosely under a
    variant have no sd: one row per variant and unit says how many, and how wide their intervals are."""
    reviewed, _, _, found, wide = _model_disagreement(classified, calibrations, core_labels, agree_sd, width_limits)
    effects = {r.model: r.effects.split("+") for r in classified.itertuples()}
    rows = [{"models": f"{d['models'][0]} / {d['models'][1]}", "term": d["label"],
             "difference": f"{abs(d['difference']):,.1f} {d['unit']}", "difference (sd)": round(d["z"], 1),
             "advice": separating_advice(effects[d["models"][0]], effects[d["models"][1]])} for d in found]
    rows += [{"models": f"{reviewed} / {other}", "term": _terms(group), "difference": _known_within(other, group),
              "difference (sd)": None, "advice": separating_advice(effects[reviewed], effects[other])}
             for other, w in wide.items() for _, group in _by_unit(w)]
    table = pd.DataFrame(rows, columns=["models", "term", "difference", "difference (sd)", "advice"])
    first = ~table["advice"].duplicated()
    return table.assign(advice=table["advice"].where(first, "")).rename(
        columns={"advice": "what would separate them"})


def sensitivity_check(classified: pd.DataFrame, calibrations: dict, core_labels: list, agree_sd: float,
                      width_limits: dict) -> Finding:
    """The verdict check "the answer does not hang on the model" (rule 3 of the module); its
    figure is the largest disagreement between the variants LOO does not reject, in combined sd
    (the report shows each, `disagreement_table`).

    ``width_limits`` maps a unit to the widest acceptable 95 % interval (the report's
    ``max_ci_width_<unit>``).
    """
    name = "the answer does not hang on the model"
    reviewed, members, every, found, wide = _model_disagreement(classified, calibrations, core_labels, agree_sd,
                                                                width_limits)
    details = {"threshold": float(agree_sd), "unit": "sd"}
    if every:
        details.update(figure=every[0]["z"], where=f"{every[0]['label']}, {' against '.join(every[0]['models'])}")
    if not found and not wide:
        why = (f"the variants LOO does not reject ({', '.join(members)}) agree on every channel-model term within "
               f"{agree_sd} combined sd, each within the interval limits" if len(members) > 1 else
               f"LOO rejects every variant but {', '.join(members)}")
        return Finding.judged(name, True, why, **details)
    effects = {r.model: r.effects.split("+") for r in classified.itertuples()}
    terms = {}  # per pair of variants, in either order: what differs, and what the other leaves unknown
    for d in found:
        terms.setdefault(frozenset(d["models"]), (d["models"], []))[1].append(
            f"{d['label']} differs by {abs(d['difference']):,.1f} {d['unit']} ({d['z']:.1f} sd)")
    for other, w in wide.items():
        terms.setdefault(frozenset((reviewed, other)), ((reviewed, other), []))[1].extend(
            f"{_terms(group)} {_known_within(other, group)}" for _, group in _by_unit(w))
    sentences = []
    for (a, b), said in terms.values():
        shown = "; ".join(said[:3]) + (f"; and {len(said) - 3} more" if len(said) > 3 else "")
        sentences.append(f"the data cannot tell {a} from {b}: {shown}. What would separate them: "
                         f"{separating_advice(effects[a], effects[b])}")
    return Finding.judged(name, False, ". ".join(sentences), **details,
                          action="fly the maneuvers that would separate the models")


def plausibility_check(classified: pd.DataFrame) -> Finding:
    """The verdict check "a plausible model": some variant neither misfits nor is LOO-rejected."""
    plausible = classified[classified["plausible"]]
    if len(plausible):
        return Finding.judged("a plausible model", True,
                              "plausible (no misfit, not rejected by leave-one-maneuver-out LOO): "
                              + ", ".join(plausible["model"]))
    return Finding.judged("a plausible model", False,
                          "every variant is rejected: " + "; ".join(f"{r.model} ({r.rejected_by})"
                                                                     for r in classified.itertuples()),
                          action="add a variant with the effect the diagnostics rank first (models:)")
