"""``calibration.csv`` (docs/interface.md section 5) and what is derived from it.

One row per parameter of the model, in the spec's order: the channel model's terms
first, channel by channel, then the extra effects' parameters in their own units; then,
channel by channel, the identifiable combinations of its scale factors (``sf_mean``,
``sf_asym``: `gyrocal.model.combinations`), derived rows that no parameter reader takes.
"""

import numpy as np
import pandas as pd

from gyrocal.model import channels as ch
from gyrocal.model.combinations import COMBINATION_NAMES, scale_combinations
from gyrocal.model.spec import ModelSpec

__all__ = ["COLUMNS", "calibration_table", "combination_rows", "core_rows", "parameter_rows", "posterior_mean_extras",
           "posterior_mean_params"]

COLUMNS = ["channel", "parameter", "unit", "point", "mean", "sd", "ci95_low", "ci95_high", "r_hat", "ess_bulk",
           "prior_only"]


def calibration_table(spec: ModelSpec, point_theta, summary: pd.DataFrame) -> pd.DataFrame:
    """The contract's table from the point estimate (SI) and the posterior summary (indexed
    by label, already in the parameters' units). A prior-only parameter's point is its
    prior mean and its posterior is its prior (`identification`)."""
    point = spec.to_unit(point_theta)
    rows = []
    for i, p in enumerate(spec.parameters):
        s = summary.loc[p.label]
        rows.append({"channel": p.owner, "parameter": p.name, "unit": p.unit, "point": point[i],
                     **{k: s[k] for k in COLUMNS[4:-1]}, "prior_only": bool(p.prior_only)})
    for c in scale_combinations(spec):
        s = summary.loc[c.label]
        rows.append({"channel": c.owner, "parameter": c.name, "unit": c.unit, "point": float(c.weights @ point),
                     **{k: s[k] for k in COLUMNS[4:-1]}, "prior_only": c.prior_only})
    return pd.DataFrame(rows, columns=COLUMNS)


def combination_rows(calibration: pd.DataFrame) -> np.ndarray:
    """Mask of the derived rows (``sf_mean``, ``sf_asym``): combinations of parameters, not parameters."""
    return calibration["parameter"].isin(COMBINATION_NAMES).to_numpy()


def parameter_rows(calibration: pd.DataFrame) -> pd.DataFrame:
    """The table without its derived rows: one row per parameter of the model, as before they existed."""
    return calibration[~combination_rows(calibration)]


def core_rows(spec: ModelSpec, calibration: pd.DataFrame) -> pd.DataFrame:
    """The rows of the channel model's terms: what the uplinked correction is made of."""
    labels = calibration["channel"] + "." + calibration["parameter"]
    return calibration[labels.isin(spec.labels[spec.core]).to_numpy()]


def posterior_mean_params(spec: ModelSpec, calibration: pd.DataFrame, bias_rad_s=None) -> ch.ChannelParams:
    """The channel model at the posterior mean (SI)."""
    mean = calibration.set_index(["channel", "parameter"])["mean"]
    theta = np.zeros(len(spec))
    theta[spec.core] = [mean[p.owner, p.name] for p in spec.parameters[spec.core]]
    return spec.channel_params(spec.to_si(theta), bias_rad_s)


def posterior_mean_extras(spec: ModelSpec, calibration: pd.DataFrame) -> np.ndarray:
    """The extra effects' parameters at the posterior mean (SI), in `ModelSpec.extras` order."""
    mean = calibration.set_index(["channel", "parameter"])["mean"]
    theta = np.zeros(len(spec))
    theta[spec.extra] = [mean[p.owner, p.name] for p in spec.extras]
    return spec.to_si(theta)[spec.extra]
