"""``model_comparison.csv``: the model variants side by side.

Residual RMS and misfit from each variant's diagnostics, PSIS-LOO over the
leave-one-block-out pointwise log-likelihood (each model's ``elpd_blocks.csv``, computed with
arviz by its posterior step) with its paired difference to the reference (the first model) and
that difference's standard error, and the parameters that moved by more than 2 sd against the
reference.
"""

import numpy as np
import pandas as pd

from gyrocal.criticism.modelchoice import classify, paired_se, reviewed_model, stacking_weights
from gyrocal.inference.sampling.predictive import PARETO_K_MAX

__all__ = ["compare", "loo_totals", "moved"]


def loo_totals(blocks: pd.DataFrame) -> dict:
    """A model's PSIS-LOO from its per-block table (`inferencedata.loo_blocks`): elpd_loo, its se
    (``sqrt(n var(elpd_i))``) and p_loo (lppd less elpd_loo), summed as arviz's ``loo`` sums them."""
    elpd = blocks["elpd_loo"].to_numpy(dtype=float)
    return {"elpd_loo": float(elpd.sum()), "elpd_loo_se": float((len(elpd) * np.var(elpd)) ** 0.5),
            "p_loo": float(np.sum(blocks["lppd"].to_numpy(dtype=float)) - elpd.sum())}


def moved(reference: pd.DataFrame, current: pd.DataFrame) -> list:
    """Labels whose posterior mean moved by more than 2 sd (the larger of the two) between two
    posterior summaries indexed by label; the noise scales are not channel parameters."""
    out = []
    for label in reference.index.intersection(current.index):
        if label.startswith("noise."):
            continue
        sd = max(reference.loc[label, "sd"], current.loc[label, "sd"])
        if abs(current.loc[label, "mean"] - reference.loc[label, "mean"]) > 2 * sd:
            out.append(label)
    return out


def compare(models, loo_blocks, diagnostics, summaries, lomo, reject_se: float) -> pd.DataFrame:
    """One row per model, in the given order; the first is the reference of the differences.

    ``lomo`` holds each model's exact leave-one-maneuver-out densities (one per maneuver):
    the criterion that decides which variants are plausible (`modelchoice`). PSIS-LOO over
    60-s blocks stays beside it: each block is predicted from its neighbours too, so it
    measures how well a model fills a gap, and sees little of a smooth effect.
    """
    reference = models[0]
    ref = loo_totals(loo_blocks[0])
    rows, loo_pointwise = [], []
    for m, d, blocks, summary in zip(models, diagnostics, loo_blocks, summaries):
        pointwise = blocks["elpd_loo"].to_numpy(dtype=float)
        loo_pointwise.append(pointwise)
        totals = loo_totals(blocks)
        k = blocks["pareto_k"].to_numpy(dtype=float)
        rows.append({"model": m, "effects": "+".join(d["effects"]),
                     "residual_rms_arcsec": d["residual_rms_arcsec"], "noise_rms_arcsec": d["noise_rms_arcsec"],
                     "misfit": d["misfit"], **totals,
                     "elpd_diff_vs_first": totals["elpd_loo"] - ref["elpd_loo"],
                     "elpd_diff_se": paired_se(pointwise - loo_pointwise[0]),
                     "pareto_k_max": float(np.max(k)), "pareto_k_over_0.7": int(np.sum(k > PARETO_K_MAX)),
                     f"moved_over_2sd_vs_{reference}": " ".join(moved(summaries[0], summary))})
    table = pd.DataFrame(rows)
    pointwise = np.array([np.asarray(v, dtype=float) for v in lomo])
    table["elpd_lomo"] = pointwise.sum(axis=1)
    table["elpd_lomo_diff_vs_first"] = table["elpd_lomo"] - table["elpd_lomo"].iloc[0]
    table["elpd_lomo_diff_se"] = [paired_se(p - pointwise[0]) for p in pointwise]
    table["stacking_weight"] = stacking_weights(pointwise) if len(models) > 1 else [1.0]
    classified = classify(table.assign(lomo_pointwise=list(pointwise), loo_pointwise=loo_pointwise), reject_se)
    table["loo_rejected"] = classified["loo_rejected"]
    table["rejected_by"] = classified["rejected_by"]
    table["plausible"] = classified["plausible"]
    table["reviewed"] = table["model"] == reviewed_model(classified)
    return table
