"""Do two trials of the same IMU agree (issue 42's must-show)? For each channel, ``sf_mean``,
``sf_pos`` and ``sf_neg`` of two runs' posteriors (``posterior.nc``, the draws of `gyrocal`'s
posterior step), and the z of their difference, ``(a - b) / sqrt(sd_a^2 + sd_b^2)``; sf_mean's sd
from the draws of (sf_pos + sf_neg) / 2, so that the two terms' correlation is kept.

    python studies/compare_trials.py results/slow/baseline/posterior.nc results/fast/baseline/posterior.nc
"""

import argparse
from pathlib import Path

import arviz as az
import numpy as np
import pandas as pd


def scale_factors(path: Path) -> pd.DataFrame:
    """Per channel and term (sf_pos, sf_neg, sf_mean): the posterior mean and sd (ppm)."""
    draws = az.from_netcdf(path).posterior["channel_param"]
    names = [str(n) for n in draws.coords["parameter"].values]
    flat = draws.values.reshape(-1, len(names))
    rows = []
    for channel in dict.fromkeys(n.split(".")[0] for n in names):
        terms = {t: flat[:, names.index(f"{channel}.{t}")] for t in ("sf_pos", "sf_neg") if f"{channel}.{t}" in names}
        if f"{channel}.sf" in names:
            terms = {"sf_mean": flat[:, names.index(f"{channel}.sf")]}
        elif len(terms) == 2:
            terms["sf_mean"] = (terms["sf_pos"] + terms["sf_neg"]) / 2
        rows += [{"channel": channel, "term": t, "mean_ppm": float(v.mean()), "sd_ppm": float(v.std(ddof=1))}
                 for t, v in terms.items()]
    return pd.DataFrame(rows).set_index(["channel", "term"])


def compare(a: pd.DataFrame, b: pd.DataFrame) -> pd.DataFrame:
    """The two runs side by side and the z of their difference."""
    both = a.merge(b, left_index=True, right_index=True, suffixes=("_a", "_b"))
    both["z"] = (both.mean_ppm_a - both.mean_ppm_b) / np.hypot(both.sd_ppm_a, both.sd_ppm_b)
    return both


def main():
    p = argparse.ArgumentParser()
    p.add_argument("a", type=Path)
    p.add_argument("b", type=Path)
    a = p.parse_args()
    print(compare(scale_factors(a.a), scale_factors(a.b)).round(2).to_string())


if __name__ == "__main__":
    main()
