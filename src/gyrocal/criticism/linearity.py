"""Is the linear error model good enough where the posterior lives?

The posterior samples a model linear in the parameters about the point estimate (`errormodel`:
``z(theta) = z(theta_hat) - S (theta - theta_hat)``, the initial attitude errors and biases
integrated out). Over large angles and fast rates the exact model bends away from that. Here the
exact model is propagated again at points on the WLS covariance's 99 % ellipsoid, where the
posterior's draws reach, with each maneuver's initial attitude error and biases at their
conditional values there (as the posterior has them), and at a tenth of the way. The mismatch
``m(d) = z_exact - z_linear`` splits into a part linear in the step ``d`` and a part quadratic in
it (`split`): the quadratic part is the exact model's curvature; the linear part is the model's
columns being averaged over a few reference intervals (`errormodel.COLUMN_WINDOW_INTERVALS`),
an intended difference from the exact derivative. What matters is how far each would move the
estimate: the mismatch, whitened and with the nuisance profiled out, regressed on the columns,
in posterior sd per parameter.
"""

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.special import gammaincinv

from gyrocal.inference import errormodel
from gyrocal.inference.fit.estimate import linearize_all
from gyrocal.maneuvers.preprocess import noise_groups
from gyrocal.model.units import ARCSEC_RAD

__all__ = ["LEVEL", "SHRINK", "check", "probe_steps", "split", "summary"]

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


def split(at_step, at_tenth, shrink: float = SHRINK) -> tuple:
    """The parts ``(a d, b d^2)`` of ``m(d) = a d + b d^2`` from ``m(d)`` and ``m(d / shrink)``."""
    quadratic = (at_step - shrink * at_tenth) / (1.0 - 1.0 / shrink)
    return at_step - quadratic, quadratic


@dataclass
class _Block:
    """One maneuver at the estimate: its linearisation, noise factor and whitened columns."""

    data: object
    lin: object
    nz: object
    chol: np.ndarray
    columns: np.ndarray
    """Whitened model columns of the free parameters."""
    nuisance: np.ndarray
    """Whitened columns of the initial attitude error and the biases."""
    profiled: np.ndarray
    """`columns` with the nuisance's span projected out."""

    def white(self, z) -> np.ndarray:
        return self.nz.whiten(self.chol, np.asfortranarray(self.nz.transform(z).reshape(-1, 1)))[:, 0]


def _blocks(maneuvers, estimate) -> list:
    lins, noises = linearize_all(maneuvers, estimate)
    index = noise_groups(maneuvers)[1]
    free = estimate.spec.free
    out = []
    for m, (data, lin, nz) in enumerate(zip(maneuvers, lins, noises)):
        chol = nz.factor(estimate.maneuver_variances(m, index[m]))
        w = nz.whiten(chol, np.asfortranarray(nz.rhs))
        columns, nuisance = w[:, :nz.n_params][:, free], w[:, nz.n_params:nz.n_params + nz.n_nuisance]
        q, _ = np.linalg.qr(nuisance)
        out.append(_Block(data, lin, nz, chol, columns, nuisance, columns - q @ (q.T @ columns)))
    return out


def _mismatch(blocks, estimate, step) -> tuple:
    """Per maneuver, exact minus linear errors at ``theta_hat + step`` with the nuisance at its
    conditional value, and the linear model's change there (rad)."""
    free = estimate.spec.free
    theta = estimate.theta.copy()
    theta[free] += step
    mismatch, change = [], []
    for m, b in enumerate(blocks):
        nuisance = -np.linalg.lstsq(b.nuisance, b.columns @ step, rcond=None)[0]
        chi0, bias = nuisance[:3], nuisance[3:]
        exact = errormodel.linearize(b.data, estimate.spec, theta, estimate.biases[m] + bias).z - chi0
        moved = -np.einsum("msap,p->msa", b.lin.design[..., free], step) - b.lin.bias_design @ bias - chi0
        mismatch.append(exact - (b.lin.z + moved))
        change.append(moved)
    return mismatch, change


def _profiled_cov(blocks) -> np.ndarray:
    """Covariance of the free parameters from the whitened columns, the nuisance profiled out."""
    return np.linalg.inv(sum(b.profiled.T @ b.profiled for b in blocks))


def _shift_sd(blocks, cov, parts) -> float:
    """The largest shift, in posterior sd (``cov``, `_profiled_cov`), that fitting ``parts`` (per
    maneuver, rad) with the linear model would give any parameter, the nuisance profiled out."""
    score = sum(b.profiled.T @ b.white(part) for b, part in zip(blocks, parts))
    return float(np.max(np.abs(cov @ score) / np.sqrt(np.diag(cov))))


def _rms_arcsec(parts) -> float:
    return float(np.sqrt(np.mean(np.concatenate([p.ravel() for p in parts]) ** 2)) / ARCSEC_RAD)


def check(maneuvers, estimate) -> pd.DataFrame:
    """One row per probe step: RMS over every sample and axis (arcsec) of the linear model's change,
    of its mismatch with the exact model and of that mismatch's parts; and the largest shift each
    part would give a parameter, in posterior sd."""
    free = estimate.spec.free
    blocks = _blocks(maneuvers, estimate)
    cov = _profiled_cov(blocks)
    rows = []
    for step in probe_steps(estimate.cov[np.ix_(free, free)]):
        full, change = _mismatch(blocks, estimate, step)
        tenth, _ = _mismatch(blocks, estimate, step / SHRINK)
        parts = [split(a, b) for a, b in zip(full, tenth)]
        columns, curvature = [p[0] for p in parts], [p[1] for p in parts]
        rows.append({"change_rms_arcsec": _rms_arcsec(change), "mismatch_rms_arcsec": _rms_arcsec(full),
                     "curvature_rms_arcsec": _rms_arcsec(curvature), "columns_rms_arcsec": _rms_arcsec(columns),
                     "curvature_shift_sd": _shift_sd(blocks, cov, curvature),
                     "columns_shift_sd": _shift_sd(blocks, cov, columns)})
    return pd.DataFrame(rows)


def summary(table: pd.DataFrame) -> str:
    """What ``gyrocal linearity`` prints under the table."""
    return (f"at the {LEVEL:.0%} ellipsoid of the WLS covariance the linear model moves the errors by up to "
            f"{table['change_rms_arcsec'].max():.3g} arcsec RMS and the exact model differs from it by up to "
            f"{table['mismatch_rms_arcsec'].max():.3g} arcsec RMS. Fitted with the linear model, the exact model's "
            f"curvature would move a parameter by at most {table['curvature_shift_sd'].max():.2g} posterior sd; "
            f"the model's averaged columns (an intended difference from the exact derivative) by at most "
            f"{table['columns_shift_sd'].max():.2g} sd")
