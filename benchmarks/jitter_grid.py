"""The posterior's noise-ratio grid with the reference's timing jitter beside correlated noise: its cost,
and how coarse it can be along each ratio. Prints figures, asserts nothing.

    python benchmarks/jitter_grid.py [--scenario tests/data/jitter_gm.yaml] [--coarse 5] [--points 40]

On a small campaign whose reference error has both (``tests/data/jitter_gm.yaml``: three fast turns,
317 star-tracker samples, one chain), the point estimates of ``st_correlated_noise`` alone and with
``st_jitter``, and per model the posterior's grid at the config's nodes (7 per ratio over +-8 sd): its
count of nodes, its build time (one BLAS thread), and the ratio of the two models'. Then, for the model
with both, grids with ``--coarse`` nodes along one ratio at a time (the config's along the others), each
against the exact log-likelihood (`likelihood.campaign_stats` at that point, the chain built at its tau),
as `benchmarks/grid_accuracy.py` checks it, at ``--points`` noise ratios drawn from the REML profile's
Laplace approximation (its full inverse Hessian: the ratios are correlated, and a point off their ridge
is one the posterior never visits): at the estimate's ``sigma_cross`` with the parameters at the point
estimate and at an offset drawn from twice the posterior's spread, and with ``sigma_cross`` at its
optimum given the ratios. Printed: the largest error in log-likelihood units, and the share of the
points inside the grid (the posterior is zero outside).
"""

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
BASE = ["scale_factor", "misalignment", "bias", "st_correlated_noise"]


def fitted(scenario, names):
    """The campaign's maneuvers, the model's point estimate, its linearisations and chains, and its priors."""
    from gyrocal.inference.fit import classic
    from gyrocal.inference.fit.estimate import linearize_all, point_estimate
    from gyrocal.inference.noise import covariance, segments
    from gyrocal.inference.sampling.priors import model_priors
    from gyrocal.maneuvers import preprocess
    from gyrocal.model import effects
    from gyrocal.model.spec import ModelSpec
    from gyrocal.simulation import simulate

    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    campaign, _ = simulate.simulate(simulate.load_scenario(scenario))
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    stated = covariance.noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    spec = ModelSpec.build("m", effects.resolve("m", names, {}), maneuvers[0].channels)
    est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    lins, _ = linearize_all(maneuvers, est)
    return est, lins, segments.Chains.of(maneuvers), model_priors(est, cfg["priors"]), cfg["grid"]


def shapes_and_sd(est, lins, chained, priors):
    """The grid's noise structures and the ratios' sd, as `posterior.prepare` gives them."""
    from gyrocal.inference.noise.covariance import noise_scales, ratios_of
    from gyrocal.inference.sampling.noisegrid import NoiseShapes, ratio_curvature

    shapes = NoiseShapes(None, lins, est.boresight, chained=chained, jitter=est.spec.jitter_noise)
    scales = noise_scales(est.spec.correlated_noise, est.spec.jitter_noise)
    return shapes, ratio_curvature(shapes, ratios_of(est.log_sigma), priors.ratio_sd(scales))


def built(shapes, ratios, sd, nodes, half_width_sd):
    """A grid and its build time (s)."""
    from gyrocal.inference.sampling.noisegrid import RatioGrid

    start = time.perf_counter()
    grid = RatioGrid(shapes, ratios, sd, nodes, half_width_sd)
    return grid, time.perf_counter() - start


def profile_covariance(shapes, ratios, step=0.02) -> np.ndarray:
    """The inverse Hessian of the REML profile at ``ratios`` (`noisegrid.ratio_curvature`'s finite
    differences, every pair): where the posterior of the ratios lies, ridges included."""
    f, k, e = shapes.profile, len(ratios), np.eye(len(ratios)) * step
    h = np.array([[(f(ratios + e[i] + e[j]) - f(ratios + e[i] - e[j]) - f(ratios - e[i] + e[j])
                    + f(ratios - e[i] - e[j])) / (4 * step**2) for j in range(k)] for i in range(k)])
    return np.linalg.inv(h)


def logliks(A, b, c, logdet, n, offsets, log_cross):
    """Per parameter offset, the log-likelihood (up to its constant) at the estimate's ``sigma_cross``;
    last, at dtheta = 0 with ``sigma_cross`` at its optimum given the ratios (where the posterior has it)."""
    scale = np.exp(2 * log_cross)
    fixed = [-0.5 * ((x @ A @ x - 2 * b @ x + c) / scale + logdet + n * np.log(scale)) for x in offsets]
    return np.array([*fixed, -0.5 * (n * np.log(c / n) + logdet + n)])


def typical_points(shapes, est, n_points, rng):
    """``n_points`` ratios drawn from the REML profile's Laplace approximation, two parameter offsets (none,
    and one drawn from twice the posterior's spread), and the exact `logliks` at each point and offset."""
    from gyrocal.inference.fit.likelihood import campaign_stats
    from gyrocal.inference.noise.covariance import ratios_of, unit_variances

    ratios, log_cross = ratios_of(est.log_sigma), est.log_sigma[0]
    center = campaign_stats(shapes.at(ratios), unit_variances(ratios))
    cov = np.linalg.pinv(center.A) * np.exp(2 * log_cross)  # prior-only parameters: no spread
    offsets = [np.zeros(len(cov)), 2 * rng.multivariate_normal(np.zeros(len(cov)), cov)]
    points = rng.multivariate_normal(ratios, profile_covariance(shapes, ratios), n_points)
    exact = []
    for p in points:
        s = campaign_stats(shapes.at(p), unit_variances(p))
        exact.append(logliks(s.A, s.b, s.c, s.logdet, s.n, offsets, log_cross))
    return points, offsets, np.array(exact)


def accuracy(grid, est, points, offsets, exact) -> str:
    """The grid's largest errors against ``exact`` at the points inside it, in words."""
    A, b, c, logdet, inside = grid.stats(points)
    values = np.array([logliks(A[i], b[i], c[i], logdet[i], grid.n, offsets, est.log_sigma[0])
                       for i in range(len(points))])
    error = np.abs(values - exact)[inside].max(axis=0) if inside.any() else np.full(3, np.nan)
    return f"inside {inside.mean():4.0%}, largest error {error[0]:.1e}, {error[1]:.1e}; profiled {error[2]:.1e}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default=str(ROOT / "tests/data/jitter_gm.yaml"))
    parser.add_argument("--coarse", type=int, default=5, help="nodes along the one coarser ratio")
    parser.add_argument("--points", type=int, default=40)
    args = parser.parse_args()
    from gyrocal.inference.noise.covariance import noise_scales, ratios_of

    rng = np.random.default_rng(0)
    print(f"errors in log-likelihood units at {args.points} noise ratios drawn from the REML profile's Laplace "
          "approximation: at the estimate's sigma_cross (dtheta 0, then an offset of twice the posterior's "
          "spread), and with sigma_cross at its optimum given the ratios (profiled)")
    seconds, sizes = {}, {}
    for names in (BASE, BASE + ["st_jitter"]):
        est, lins, chained, priors, grid_cfg = fitted(args.scenario, names)
        shapes, sd = shapes_and_sd(est, lins, chained, priors)
        ratios = ratios_of(est.log_sigma)
        grid, seconds[names[-1]] = built(shapes, ratios, sd, grid_cfg["nodes"], grid_cfg["half_width_sd"])
        sizes[names[-1]] = grid.size
        checks = typical_points(shapes, est, args.points, rng)
        print(f"{names[-1]}: {grid.size} nodes, grid built in {seconds[names[-1]]:.1f} s "
              f"({1e3 * seconds[names[-1]] / grid.size:.2f} ms a node); ratios {ratios.round(3)}, sd {sd.round(3)}; "
              f"{accuracy(grid, est, *checks)}", flush=True)
    print(f"with the jitter: {sizes['st_jitter'] / sizes['st_correlated_noise']:.1f} times the nodes, "
          f"{seconds['st_jitter'] / seconds['st_correlated_noise']:.1f} times the time")
    names = [s.key for s in noise_scales(True, True)[1:]]
    for axis in range(len(ratios)):
        nodes = np.full(len(ratios), grid_cfg["nodes"])
        nodes[axis] = args.coarse
        coarse, taken = built(shapes, ratios, sd, nodes, grid_cfg["half_width_sd"])
        print(f"{tuple(int(n) for n in nodes)} ({names[axis]} at {args.coarse}): {coarse.size} nodes in {taken:.1f} s, "
              f"{accuracy(coarse, est, *checks)}", flush=True)

if __name__ == "__main__":
    main()
