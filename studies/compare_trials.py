"""Do two trials of the same IMU agree (issue 42's must-show)? For each channel, ``sf_mean``,
``sf_pos`` and ``sf_neg``, and for each pair of a channel set its non-orthogonality (90 deg less the
angle between the two sensing axes, `gyrocal.model.orthogonality`, arcsec), from two runs'
posteriors (``posterior.nc``, the draws of `gyrocal`'s posterior step, with the run's
``point_estimate.npz`` and ``correction.json`` beside it for the spec and the channel sets), and the
z of their difference, ``(a - b) / sqrt(sd_a^2 + sd_b^2)``. Each derived quantity is computed draw
by draw (sf_mean = (sf_pos + sf_neg) / 2; the non-orthogonality from the misalignments), so that the
terms' correlation is kept. Neither depends on the reference frame, so the two runs' estimated
mountings need no turning (the misalignments themselves do: ``gyrocal compare-campaigns``).
``prior_part`` marks a row with a prior-only part in either run (a y-only trial leaves the
misalignments toward pitch's neighbours' opposite terms to the prior): its z says little.

``--point`` takes each run's point estimate instead, its WLS mean and covariance as a normal (drawn
with a fixed seed, the channel sets from its maneuvers): what a model tells where the workflow refused
to sample it, not a posterior.

    python studies/compare_trials.py results/slow/baseline results/fast/baseline [--point]
"""

import argparse
import json
from pathlib import Path

import arviz as az
import numpy as np
import pandas as pd

from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.model import combinations, orthogonality
from gyrocal.pipeline.readback import load_model_run


def scale_factors(spec, values) -> list:
    """Per channel, in the spec's order: ``sf_pos`` and ``sf_neg`` where sampled, and ``sf_mean``
    (`combinations.scale_combinations`), each as its draws (ppm, from ``values`` in the spec's order)
    and whether a part is prior-only."""
    means = {c.owner: (c, k) for k, c in enumerate(
        [c for c in combinations.scale_combinations(spec) if c.name == "sf_mean"])}
    mean_draws = combinations.combination_draws(values, [c for c, _ in means.values()])
    rows = []
    for channel in spec.channels:
        for name in ("sf_pos", "sf_neg"):
            if (label := f"{channel.name}.{name}") in spec.labels:
                i = spec.labels.index(label)
                rows.append((channel.name, name, values[:, i], bool(spec.parameters[i].prior_only)))
        if channel.name in means:
            c, k = means[channel.name]
            parts = np.flatnonzero(c.weights)
            rows.append((channel.name, "sf_mean", mean_draws[:, k], any(bool(spec.parameters[i].prior_only) for i in parts)))
    return rows


POINT_DRAWS = 20000
"""Draws of a point estimate's normal (`point_draws`): sd to 0.5 %."""


def posterior_draws(run: Path) -> tuple:
    """The spec, the channel parameters' posterior draws (in its order and units) and the channel sets."""
    draws = az.from_netcdf(run / "posterior.nc").posterior["channel_param"]
    names = [str(n) for n in draws.coords["parameter"].values]
    spec = PointEstimate.load(run / "point_estimate.npz", linearizations=False).spec
    values = draws.values.reshape(-1, len(names))[:, [names.index(label) for label in spec.labels]]
    return spec, values, [tuple(s["channels"]) for s in json.loads((run / "correction.json").read_text())["sets"]]


def point_draws(run: Path) -> tuple:
    """`posterior_draws` of the point estimate: its WLS ``theta`` and ``cov`` as a normal, in the spec's units."""
    maneuvers, est = load_model_run(run.parent, run.name)
    scale = est.spec.si_per_unit
    values = np.random.default_rng(0).multivariate_normal(est.theta / scale, est.cov / np.outer(scale, scale),
                                                          POINT_DRAWS)
    return est.spec, values, [tuple(s) for s in maneuvers[0].sets]


def summaries(run: Path, point: bool = False) -> pd.DataFrame:
    """One run's (``<results>/<campaign>/<model>``) sf_pos, sf_neg, sf_mean and non-orthogonality: mean,
    sd (from the draws) and unit, indexed by channel (or pair) and term; ``point``: of its point estimate."""
    spec, values, sets = (point_draws if point else posterior_draws)(run)
    prior_only = {p.label for p in spec.parameters if p.prior_only}
    rows = [{"channel": c, "term": t, "unit": "ppm", "mean": float(v.mean()), "sd": float(v.std(ddof=1)),
             "prior_part": part} for c, t, v, part in scale_factors(spec, values)]
    pairs = orthogonality.pairs(spec, sets)
    if pairs:
        values = orthogonality.pair_draws(values, spec, pairs)
        for k, p in enumerate(pairs):
            (a, b), (i, j) = p.axes, p.channels
            rows.append({"channel": "+".join(p.channels), "term": p.name, "unit": "arcsec",
                         "mean": float(values[:, k].mean()), "sd": float(values[:, k].std(ddof=1)),
                         "prior_part": f"{i}.mis_{b}" in prior_only or f"{j}.mis_{a}" in prior_only})
    return pd.DataFrame(rows).set_index(["channel", "term"])


def compare(a: pd.DataFrame, b: pd.DataFrame) -> pd.DataFrame:
    """The two runs side by side and the z of their difference."""
    both = a.merge(b.drop(columns="unit"), left_index=True, right_index=True, suffixes=("_a", "_b"))
    both["z"] = (both.mean_a - both.mean_b) / np.hypot(both.sd_a, both.sd_b)
    both["prior_part"] = both.pop("prior_part_a") | both.pop("prior_part_b")
    return both


def main():
    p = argparse.ArgumentParser()
    p.add_argument("a", type=Path, help="one run's model folder, results/<campaign>/<model>")
    p.add_argument("b", type=Path)
    p.add_argument("--point", action="store_true", help="compare the point estimates (WLS mean and covariance)")
    a = p.parse_args()
    table = compare(summaries(a.a, a.point), summaries(a.b, a.point))
    print(table.round(2).to_string())
    informed = table[~table["prior_part"]]
    print(f"largest |z| where no part is prior-only: {informed['z'].abs().max():.2f} over {len(informed)} terms; "
          f"beyond 3: {int((informed['z'].abs() > 3).sum())}")


if __name__ == "__main__":
    main()
