"""Two calibrations of the same gyros, parameter by parameter: do they agree within their uncertainty?

The same sensor calibrated twice (two trials, two campaigns) must give answers that differ by
no more than their intervals allow. For each parameter both ``calibration.csv`` files hold,
``z = (mean_B - mean_A) / sqrt(sd_A^2 + sd_B^2)``: independent campaigns, normal posteriors.
"""

import numpy as np
import pandas as pd

KEYS = ["channel", "parameter"]


def compare(first: pd.DataFrame, second: pd.DataFrame) -> pd.DataFrame:
    """One row per parameter both tables hold: means, sds, difference, its sd and z. A parameter
    prior-only in either is listed with no z (the data said nothing to compare)."""
    merged = first.merge(second, on=KEYS, suffixes=("_a", "_b"), how="inner", validate="one_to_one")
    units = merged["unit_a"] != merged["unit_b"]
    if units.any():
        row = merged[units].iloc[0]
        raise ValueError(f"{row.channel}.{row.parameter} is in {row.unit_a} in the first file, {row.unit_b} in the second")
    prior_only = np.zeros(len(merged), dtype=bool)
    for column in ("prior_only_a", "prior_only_b"):
        if column in merged:
            prior_only |= merged[column].fillna(False).astype(bool).to_numpy()
    diff = merged["mean_b"] - merged["mean_a"]
    sd = np.hypot(merged["sd_a"], merged["sd_b"])
    return pd.DataFrame({"channel": merged["channel"], "parameter": merged["parameter"], "unit": merged["unit_a"],
                         "mean_a": merged["mean_a"], "sd_a": merged["sd_a"], "mean_b": merged["mean_b"],
                         "sd_b": merged["sd_b"], "difference": diff, "difference_sd": sd,
                         "z": np.where(prior_only, np.nan, diff / sd), "prior_only": prior_only})


def compare_files(first, second, z_max: float = 3.0) -> tuple:
    """``gyrocal compare-campaigns``: the table as text, a verdict line, and whether they agree."""
    table = compare(pd.read_csv(first), pd.read_csv(second))
    compared = table[~table["prior_only"]]
    worst = compared.loc[compared["z"].abs().idxmax()] if len(compared) else None
    agree = bool(len(compared)) and bool((compared["z"].abs() < z_max).all())
    out = [f"A = {first}", f"B = {second}", table.round(3).to_string(index=False)]
    if worst is None:
        out.append("VERDICT: nothing to compare (no parameter informed in both)")
    else:
        out.append(f"VERDICT: {'AGREE' if agree else 'DISAGREE'}: {int((compared['z'].abs() >= z_max).sum())} of "
                   f"{len(compared)} parameters beyond |z| = {z_max:g}; largest {worst.channel}.{worst.parameter} "
                   f"z = {worst.z:+.2f}")
    return "\n".join(out), agree
