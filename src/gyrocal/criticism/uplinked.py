"""The posterior of what is uplinked. Where the model's scale factor changes with the rate (an
operating-scale effect, `gyrocal.inference.fit.operating`), ``correction.json`` carries each direction's
scale factor at the campaign's rates, not the zero-rate intercept ``calibration.csv`` lists: one rate a
direction leaves the intercept as wide as the growth's prior while the uplinked value is known. The
precision check and the review's resolution table judge the uplinked values: each posterior draw's scale
factors plus the growth its own coefficients give, and their combinations (``sf_mean``, ``sf_asym``)."""

import numpy as np
import pandas as pd

from gyrocal.inference.sampling.inferencedata import CI_PROB
from gyrocal.model import combinations as comb

__all__ = ["COLUMNS", "at_uplink", "flown_intervals", "uplinked_intervals"]

COLUMNS = ["channel", "parameter", "unit", "mean", "sd", "ci95_low", "ci95_high"]
"""`flown_intervals`' columns: ``calibration.csv``'s summary, which `at_uplink` replaces."""

SCALE_FACTORS = ("sf", "sf_pos", "sf_neg")


def flown_intervals(values, spec, shift_map: np.ndarray) -> pd.DataFrame:
    """Each scale-factor term's posterior as uplinked, at the campaign's rates, and its combinations':
    ``values`` (..., len(spec)) are posterior draws in the parameters' units, ``shift_map``
    `gyrocal.inference.fit.operating.operating_map`'s. Each draw's term plus what its own operating-scale
    parameters add (row 1 of the map for ``sf_neg``, row 0 otherwise), then ``sf_mean`` and ``sf_asym`` of
    those draws; mean, sd and the central `CI_PROB` interval as ``calibration.csv`` computes them."""
    values = np.asarray(values, dtype=float).reshape(-1, len(spec))
    shift_si = np.einsum("rce,de->drc", shift_map, spec.to_si(values)[:, spec.extra])
    index = {c.name: i for i, c in enumerate(spec.channels)}
    flown = values.copy()
    terms = [(j, p) for j, p in enumerate(spec.parameters[spec.core]) if p.name in SCALE_FACTORS]
    if not terms:
        return pd.DataFrame(columns=COLUMNS)
    for j, p in terms:
        flown[:, j] += shift_si[:, int(p.name == "sf_neg"), index[p.owner]] / spec.si_per_unit[j]
    combos = comb.scale_combinations(spec)
    named = [(p.owner, p.name, p.unit, flown[:, j]) for j, p in terms]
    named += [(c.owner, c.name, spec.units[terms[0][0]], d) for c, d in zip(combos, comb.combination_draws(flown, combos).T)]
    tail = (1.0 - CI_PROB) / 2.0
    rows = [{"channel": owner, "parameter": name, "unit": unit, "mean": float(d.mean()), "sd": float(d.std(ddof=1)),
             **dict(zip(("ci95_low", "ci95_high"), map(float, np.quantile(d, [tail, 1.0 - tail]))))}
            for owner, name, unit, d in named]
    return pd.DataFrame(rows, columns=COLUMNS)


def uplinked_intervals(posterior, spec, shift_map: np.ndarray) -> pd.DataFrame | None:
    """`flown_intervals` of the posterior draws (an InferenceData's ``channel_param``) at the campaign's
    rates (``shift_map``: `operating_map` of its maneuvers and the fit's biases), where the model's scale
    factor changes with the rate (the map not all zero); None where it does not."""
    if not shift_map.any():
        return None
    return flown_intervals(posterior.posterior["channel_param"].values, spec, shift_map)


def at_uplink(calibration: pd.DataFrame, flown: pd.DataFrame | None) -> pd.DataFrame:
    """``calibration`` (a ``calibration.csv``) with the rows ``flown`` holds (`uplinked_intervals`)
    summarised as uplinked: their mean, sd and interval replaced; itself where ``flown`` is None."""
    if flown is None or flown.empty:
        return calibration
    keys = ["channel", "parameter"]
    out = calibration.set_index(keys)
    out.update(flown.set_index(keys)[COLUMNS[3:]])
    return out.reset_index()[calibration.columns]
