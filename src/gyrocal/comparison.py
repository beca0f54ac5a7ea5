"""``model_comparison.csv``: the model variants side by side.

Residual RMS and misfit from each variant's diagnostics, PSIS-LOO (arviz) over the
leave-one-block-out pointwise log-likelihood with its paired difference to the
reference (the first model) and that difference's standard error, and the
parameters that moved by more than 2 sd against the reference.
"""

import logging
import warnings

import arviz as az
import numpy as np
import pandas as pd

from .inferencedata import NOISE_LABELS
from .modelchoice import classify, paired_se, reviewed_model, stacking_weights

log = logging.getLogger("gyrocal")


def loo(idata, model: str):
    """PSIS-LOO of one model and its count of Pareto k > 0.7 blocks. arviz warns about those
    blocks (the posterior cannot importance-sample their leave-out posterior); the count
    goes in the table and the log says what it means, instead of a bare warning."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Estimated shape parameter of Pareto", category=UserWarning)
        result = az.loo(idata, pointwise=True)
    high = int(np.sum(result.pareto_k.values > 0.7))
    if high:
        log.info("PSIS-LOO for model %s: %d of %d blocks have Pareto k > 0.7, so its elpd_loo is less "
                 "reliable; typical of a misfitting model, whose residual blocks are influential",
                 model, high, result.pareto_k.size)
    return result, high


def moved(reference: pd.DataFrame, current: pd.DataFrame) -> list:
    """Labels whose posterior mean moved by more than 2 sd (the larger of the two) between two
    posterior summaries indexed by label; the noise scales are not channel parameters."""
    out = []
    for label in reference.index.intersection(current.index):
        if label in NOISE_LABELS:
            continue
        sd = max(reference.loc[label, "sd"], current.loc[label, "sd"])
        if abs(current.loc[label, "mean"] - reference.loc[label, "mean"]) > 2 * sd:
            out.append(label)
    return out


def compare(models, idatas, diagnostics, summaries, lomo, reject_se: float) -> pd.DataFrame:
    """One row per model, in the given order; the first is the reference of the differences.

    ``lomo`` holds each model's exact leave-one-maneuver-out densities (one per maneuver):
    the criterion that decides which variants are plausible (`modelchoice`). PSIS-LOO over
    60-s blocks stays beside it: each block is predicted from its neighbours too, so it
    measures how well a model fills a gap, and sees little of a smooth effect.
    """
    loos = [loo(idata, m) for m, idata in zip(models, idatas)]
    reference = models[0]
    ref_loo = loos[0][0]
    rows, loo_pointwise = [], []
    for m, d, (result, high), summary in zip(models, diagnostics, loos, summaries):
        loo_pointwise.append(result.loo_i.values)
        paired = result.loo_i.values - ref_loo.loo_i.values
        rows.append({"model": m, "effects": "+".join(d["effects"]),
                     "residual_rms_arcsec": d["residual_rms_arcsec"], "noise_rms_arcsec": d["noise_rms_arcsec"],
                     "misfit": d["misfit"], "elpd_loo": float(result.elpd_loo), "elpd_loo_se": float(result.se),
                     "p_loo": float(result.p_loo),
                     "elpd_diff_vs_first": float(result.elpd_loo - ref_loo.elpd_loo),
                     "elpd_diff_se": paired_se(paired),
                     "pareto_k_max": float(np.max(result.pareto_k.values)), "pareto_k_over_0.7": high,
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
