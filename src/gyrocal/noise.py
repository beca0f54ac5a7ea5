"""The noise model of the attitude error, as a banded covariance per maneuver.

Two sources shape the error series: the star tracker's white noise, anisotropic about
its boresight (shared by every channel set, since all are compared with the same
star-tracker sample), and the gyros' angle random walk, which accumulates in the
propagated attitude. Taking first differences in time (the first sample kept) turns
the walk into white noise and the star-tracker noise into an MA(1) process, so the
covariance of the differenced, set-stacked series is block tridiagonal: O(N) to
factor with LAPACK's banded Cholesky. Its three components are linear in
``sigma_cross^2``, ``sigma_about^2`` and ``ARW^2``.
"""

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cholesky_banded
from scipy.linalg.lapack import dtbtrs

from .errormodel import Linearization

COMPONENTS = ("cross", "about", "walk")


def _banded_lower(diag_blocks, lower_blocks):
    """LAPACK lower band storage of a symmetric block-tridiagonal matrix."""
    n_blocks, m, _ = diag_blocks.shape
    kd = 2 * m - 1
    ab = np.zeros((kd + 1, n_blocks * m))
    a, b = np.tril_indices(m)
    starts = m * np.arange(n_blocks)
    rows = (starts[:, None] + a[None]).ravel()
    cols = (starts[:, None] + b[None]).ravel()
    ab[rows - cols, cols] = diag_blocks[:, a, b].ravel()
    if n_blocks > 1:
        a, b = np.indices((m, m)).reshape(2, -1)
        rows = (starts[1:, None] + a[None]).ravel()
        cols = (starts[:-1, None] + b[None]).ravel()
        ab[rows - cols, cols] = lower_blocks[:, a, b].ravel()
    return ab


def difference(series: np.ndarray) -> np.ndarray:
    """First differences along time with the first sample kept (the transform above)."""
    return np.concatenate([series[:1], np.diff(series, axis=0)])


@dataclass
class ManeuverNoise:
    """Banded covariance components and the differenced right-hand sides of one maneuver."""

    maneuver: str
    components: dict
    """name -> (kd+1, n) lower band storage, per unit variance."""
    rhs: np.ndarray
    """(n, P + G + 1): differenced design, nuisance design and data, flattened."""
    n_params: int
    n_nuisance: int

    @property
    def n(self) -> int:
        return self.rhs.shape[0]

    def covariance(self, variances: dict) -> np.ndarray:
        return sum(variances[k] * self.components[k] for k in COMPONENTS)

    def factor(self, variances: dict) -> np.ndarray:
        return cholesky_banded(self.covariance(variances), lower=True)

    def gram(self, variances: dict):
        """``rhs^T C^-1 rhs`` and ``log det C``."""
        chol = self.factor(variances)
        white = self.whiten(chol, self.rhs)
        return white.T @ white, 2.0 * np.sum(np.log(chol[0]))

    def whiten(self, chol: np.ndarray, x: np.ndarray) -> np.ndarray:
        """``L^-1 x`` for the banded Cholesky factor ``L``."""
        x2 = x.reshape(len(x), -1)
        out, info = dtbtrs(chol, x2, uplo="L")
        if info != 0:
            raise np.linalg.LinAlgError(f"banded triangular solve failed (info={info})")
        return out.reshape(x.shape)


def nuisance_design(lin: Linearization) -> np.ndarray:
    """(M, S, 3, 3 + n_channels): initial attitude error ``chi0`` (shared) and biases."""
    m, n_sets = lin.z.shape[:2]
    chi0 = np.zeros((m, n_sets, 3, 3))
    chi0[:, :, np.arange(3), np.arange(3)] = 1.0
    return np.concatenate([chi0, lin.bias_design], axis=3)


def build(lin: Linearization, boresight_body) -> ManeuverNoise:
    """Covariance components and differenced right-hand sides of a linearised maneuver."""
    m_samples, n_sets = lin.z.shape[:2]
    block = 3 * n_sets
    b = np.asarray(boresight_body, dtype=float)
    b = b / np.linalg.norm(b)
    about_body = np.outer(b, b)
    ones = np.ones((n_sets, n_sets))
    R = lin.st_matrix
    diag, lower = {}, {}
    for name, body_cov in (("cross", np.eye(3) - about_body), ("about", about_body)):
        u = np.einsum("jab,bc,jdc->jad", R, body_cov, R)
        u = np.einsum("st,jab->jsatb", ones, u).reshape(m_samples, block, block)
        d = u.copy()
        d[1:] += u[:-1]
        diag[name], lower[name] = d, -u[:-1]
    walk = lin.shared_walk.transpose(0, 1, 3, 2, 4).reshape(m_samples, block, block)
    diag["walk"], lower["walk"] = walk, np.zeros((max(m_samples - 1, 0), block, block))
    components = {k: _banded_lower(diag[k], lower[k]) for k in COMPONENTS}
    nuis = difference(nuisance_design(lin))
    n = m_samples * block
    rhs = np.concatenate([
        difference(lin.design).reshape(n, -1),
        nuis.reshape(n, -1),
        difference(lin.z).reshape(n, 1),
    ], axis=1)
    return ManeuverNoise(lin.maneuver, components, rhs, lin.design.shape[-1], nuis.shape[-1])
