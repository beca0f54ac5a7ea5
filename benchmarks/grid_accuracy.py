"""How coarse the noise-ratio grid can be: prints figures, asserts nothing.

    python benchmarks/grid_accuracy.py

On the default MOM-like campaign (simulated, preprocessed, WLS for the baseline model), the
posterior's log-likelihood from the grid's cubic interpolation (`noisegrid.RatioGrid`) is
compared with the exact one (`likelihood.campaign_stats` at that point) at 40 noise ratios
within 2 of their sd, at the point estimate and at a parameter offset drawn from twice the
posterior's spread. Printed per grid (nodes per side, half width in sd): its build time,
and the largest error in log-likelihood units. The sampler's accept decisions compare
log densities, so an error far below 1 changes nothing but rounding.
"""

import time
from pathlib import Path

import numpy as np
import yaml
from simulated import baseline_fit

ROOT = Path(__file__).resolve().parents[1]
GRIDS = [(11, 7.0), (9, 7.0), (7, 8.0), (5, 8.0)]


def main():
    from gyrocal.inference.fit.estimate import linearize_all
    from gyrocal.inference.fit.likelihood import campaign_stats
    from gyrocal.inference.noise.covariance import ratios_of, unit_variances
    from gyrocal.inference.sampling import noisegrid

    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    fitted = baseline_fit(ROOT / "config/scenarios/mom.yaml", cfg)
    maneuvers, est, priors, spec = fitted.maneuvers, fitted.estimate, fitted.priors, fitted.estimate.spec
    _, noises = linearize_all(maneuvers, est)
    ratios = ratios_of(est.log_sigma)
    ratio_sd = noisegrid.ratio_curvature(noises, ratios, priors.log_ratio_sd)
    scale = np.exp(2 * est.log_sigma[0])
    rng = np.random.default_rng(0)
    points = ratios + ratio_sd * rng.uniform(-2, 2, (40, 2))
    exact = [campaign_stats(noises, unit_variances(r)) for r in points]
    offset = 2 * rng.multivariate_normal(np.zeros(len(spec)), np.linalg.inv(exact[0].A) * scale)
    print(f"noise ratios {ratios.round(3)}, their sd {ratio_sd.round(4)}; errors in log-likelihood units")
    for nodes, half_width in GRIDS:
        start = time.perf_counter()
        grid = noisegrid.RatioGrid(noises, ratios, ratio_sd, nodes, half_width)
        build_s = time.perf_counter() - start
        A, b, c, logdet, inside = grid.stats(points)
        errors = [abs(0.5 * ((x @ A[k] @ x - 2 * b[k] @ x + c[k]) - (x @ s.A @ x - 2 * s.b @ x + s.c)) / scale
                      + 0.5 * (logdet[k] - s.logdet))
                  for k, s in enumerate(exact) for x in (np.zeros(len(spec)), offset)]
        print(f"{nodes:2d} x {nodes:2d} nodes over +-{half_width:g} sd: built in {build_s:5.2f} s, "
              f"inside {inside.mean():.0%}, largest error {max(errors):.2e}")


if __name__ == "__main__":
    main()
