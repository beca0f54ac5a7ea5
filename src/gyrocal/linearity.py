"""Is the linear error model good enough where the posterior lives?

The posterior samples a model linear in the parameters about the point estimate (`errormodel`:
``z(theta) = z(theta_hat) - S (theta - theta_hat)``). Over large angles and fast rates the exact
model bends away from that. Here the exact model is propagated again at points on the WLS
covariance's 99 % ellipsoid, where the posterior's draws reach, and at a tenth of the way there:
the mismatch ``m(d) = z_exact(theta_hat + d) - z_linear(theta_hat + d)`` splits into a part
linear in ``d`` (the model's columns are averaged over a few star-tracker intervals, so they
differ from the exact derivative where the rate changes fast) and a part quadratic in ``d``
(the curvature of the exact model), as ``m(d) = a d + b d^2`` gives them from ``m(d)`` and
``m(d / 10)``.
"""

import numpy as np
import pandas as pd
from scipy.special import gammaincinv

from . import errormodel
from .units import ARCSEC_RAD

LEVEL = 0.99
"""The probe points sit on this credible ellipsoid of the WLS covariance."""

SHRINK = 10.0
"""The second probe of each direction is this many times closer to the estimate."""


def probe_steps(cov_free: np.ndarray, level: float = LEVEL) -> np.ndarray:
    """(4, n) parameter steps on the ``level`` ellipsoid of ``cov_free``: ``+-L u`` along two fixed
    whitened directions (all parameters together, and alternating signs), ``L`` its Cholesky
    factor. Any direction of the ellipsoid is as likely under the posterior; these two move every
    parameter at once, and deterministically."""
    n = len(cov_free)
    radius = np.sqrt(2.0 * gammaincinv(n / 2.0, level))
    ones = np.ones(n) / np.sqrt(n)
    alternating = np.where(np.arange(n) % 2 == 0, 1.0, -1.0) / np.sqrt(n)
    factor = np.linalg.cholesky(cov_free)
    directions = np.array([ones, -ones, alternating, -alternating]) * radius
    return directions @ factor.T


def _errors(maneuvers, estimate, theta) -> np.ndarray:
    """Every maneuver's inertial-frame errors at ``theta`` (exact model), stacked (rad)."""
    return np.concatenate([errormodel.linearize(d, estimate.spec, theta, estimate.biases[m]).z.ravel()
                           for m, d in enumerate(maneuvers)])


def check(maneuvers, estimate) -> pd.DataFrame:
    """One row per probe step: RMS over every sample and axis (arcsec) of the linear model's change
    there, of its mismatch with the exact model, and of that mismatch's linear and quadratic parts."""
    free = estimate.spec.free
    lins = [errormodel.linearize(d, estimate.spec, estimate.theta, estimate.biases[m]) for m, d in enumerate(maneuvers)]
    z0 = np.concatenate([lin.z.ravel() for lin in lins])
    design = np.concatenate([lin.design[..., free].reshape(-1, int(free.sum())) for lin in lins])
    rows = []
    for step in probe_steps(estimate.cov[np.ix_(free, free)]):
        mismatch = []
        for d in (step, step / SHRINK):
            theta = estimate.theta.copy()
            theta[free] += d
            mismatch.append(_errors(maneuvers, estimate, theta) - (z0 - design @ d))
        quadratic = (mismatch[0] - SHRINK * mismatch[1]) / (1.0 - 1.0 / SHRINK)
        change = design @ step
        rows.append({name: float(np.sqrt(np.mean(x**2)) / ARCSEC_RAD) for name, x in (
            ("change_rms_arcsec", change), ("mismatch_rms_arcsec", mismatch[0]),
            ("linear_part_rms_arcsec", mismatch[0] - quadratic), ("quadratic_part_rms_arcsec", quadratic))})
    return pd.DataFrame(rows)


def summary(table: pd.DataFrame, residual_rms_arcsec: float) -> str:
    """What ``gyrocal linearity`` prints under the table."""
    worst = table.loc[table["mismatch_rms_arcsec"].idxmax()]
    return (f"at the {LEVEL:.0%} ellipsoid of the WLS covariance the linear model moves the errors by "
            f"{table['change_rms_arcsec'].max():.3g} arcsec RMS; the exact model differs from it by at most "
            f"{worst['mismatch_rms_arcsec']:.3g} arcsec RMS ({worst['mismatch_rms_arcsec'] / worst['change_rms_arcsec']:.1%} "
            f"of the change; quadratic, the exact model's curvature: {table['quadratic_part_rms_arcsec'].max():.3g}; "
            f"linear, the averaged columns: {table['linear_part_rms_arcsec'].max():.3g})"
            + (f", against a residual RMS of {residual_rms_arcsec:.4g} arcsec" if np.isfinite(residual_rms_arcsec)
               else " (no diagnostics.json: no residual RMS to set it against)"))


def run(results, model: str, plugin_paths=()) -> str:
    """``gyrocal linearity``: the check on one model of a finished run (its preprocessed maneuvers
    and point estimate), as a table and a summary line."""
    import json
    from pathlib import Path

    from .estimate import PointEstimate
    from .steps.common import known_effects, load_maneuvers
    results = Path(results)
    point = results / model / "point_estimate.npz"
    if not point.is_file():
        raise FileNotFoundError(f"{point}: no point estimate of model {model!r} in {results} (run the pipeline first)")
    ids = json.loads((results / "input.json").read_text())["maneuvers"]
    maneuvers = load_maneuvers([results / "preprocess" / f"{i}.npz" for i in ids])
    estimate = PointEstimate.load(point, known_effects(list(plugin_paths)))
    table = check(maneuvers, estimate)
    diagnostics = results / model / "diagnostics.json"
    residual = json.loads(diagnostics.read_text())["residual_rms_arcsec"] if diagnostics.is_file() else float("nan")
    return f"{results}, model {model}\n{table.round(3).to_string()}\n{summary(table, residual)}"
