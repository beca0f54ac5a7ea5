"""``orthogonality.csv`` (docs/interface.md section 5): per channel set, the non-orthogonality of
each pair of its channels (`gyrocal.model.orthogonality`), beside ``calibration.csv``'s ``sf_mean``:
a table of its own, so that ``calibration.csv`` keeps its rows."""

import pandas as pd

from gyrocal.model import orthogonality
from gyrocal.model.spec import ModelSpec

__all__ = ["COLUMNS", "orthogonality_table"]

COLUMNS = ["set", "channels", "parameter", "unit", "definition", "point", "mean", "sd", "ci95_low", "ci95_high",
           "r_hat", "ess_bulk", "prior_only"]


def orthogonality_table(spec: ModelSpec, point_theta, pairs, summary: pd.DataFrame | None) -> pd.DataFrame:
    """The contract's table from the point estimate (SI), the channel sets' ``pairs`` and their
    posterior ``summary`` (indexed by the pairs' labels, arcsec; `inferencedata.orthogonality_summary`);
    no rows for a model without misalignments."""
    point = orthogonality.pair_draws(spec.to_unit(point_theta), spec, pairs) if pairs else []
    rows = []
    for p, value in zip(pairs, point, strict=True):
        s = summary.loc[p.label]
        rows.append({"set": p.set, "channels": "+".join(p.channels), "parameter": p.name, "unit": "arcsec",
                     "definition": p.definition, "point": float(value),
                     **{k: s[k] for k in COLUMNS[6:-1]}, "prior_only": p.prior_only})
    return pd.DataFrame(rows, columns=COLUMNS)
