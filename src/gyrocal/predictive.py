"""Residuals, pointwise log-likelihood and posterior-predictive draws of the attitude error.

These evaluate the sampled posterior against the data: per draw the nuisance
(initial attitude error, biases) is set to its conditional least-squares value, the
residual is formed in the inertial frame and rotated into body axes, and noise
replicates come from the banded covariance of `noise`.
"""

import numpy as np

from .errormodel import Linearization
from .estimate import variances
from .noise import ManeuverNoise, nuisance_design


class WhitenedManeuver:
    """One maneuver whitened at fixed noise ratios (unit cross-boresight variance)."""

    def __init__(self, noise: ManeuverNoise, ratios):
        self.noise = noise
        self.chol = noise.factor(variances([0.0, ratios[0], ratios[1]]))
        self.white = noise.whiten(self.chol, noise.rhs)
        p, g = noise.n_params, noise.n_nuisance
        self.wx, self.wg, self.wd = self.white[:, :p], self.white[:, p:p + g], self.white[:, -1]
        self.gram_g = self.wg.T @ self.wg

    def nuisance(self, dtheta: np.ndarray) -> np.ndarray:
        """(D, G) conditional least-squares nuisance for each row of ``dtheta``."""
        target = self.wd[:, None] - self.wx @ dtheta.T
        return np.linalg.solve(self.gram_g, self.wg.T @ target).T

    def pointwise_loglik(self, dtheta, beta, scale, block_of_row):
        """(D, n_blocks) log density of the whitened innovations, summed per block.

        The Cholesky factor orders the innovations in time, so each block's sum is its
        log density given the blocks before it (``scale`` is sigma_cross^2 per draw).
        """
        w = self.wd[None, :] - dtheta @ self.wx.T - beta @ self.wg.T
        log_diag = np.log(self.chol[0])
        dens = -0.5 * (w**2 / scale[:, None] + np.log(2 * np.pi * scale)[:, None]) - log_diag[None, :]
        n_blocks = block_of_row.max() + 1
        out = np.zeros((len(dtheta), n_blocks))
        np.add.at(out.T, block_of_row, dens.T)
        return out

    def noise_draws(self, scale, rng) -> np.ndarray:
        """(D, n) differenced noise replicates ``sqrt(scale) L xi``."""
        xi = rng.standard_normal((len(scale), self.chol.shape[1]))
        out = np.zeros_like(xi)
        n = xi.shape[1]
        for k in range(self.chol.shape[0]):
            out[:, k:] += self.chol[k, :n - k] * xi[:, :n - k]
        return out * np.sqrt(scale)[:, None]


def residuals_body(lin: Linearization, dtheta: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """(D, M, S, 3) star tracker minus model, in body axes (rad), per draw."""
    nuis = nuisance_design(lin)
    fitted = np.einsum("msip,dp->dmsi", lin.design, dtheta) + np.einsum("msig,dg->dmsi", nuis, beta)
    resid = lin.z[None] - fitted
    return np.einsum("mji,dmsj->dmsi", lin.st_matrix, resid)


def undifference_body(lin: Linearization, differenced: np.ndarray) -> np.ndarray:
    """(D, M, S, 3) body-axis series from differenced inertial series (D, n)."""
    m, s = lin.z.shape[:2]
    inertial = np.cumsum(differenced.reshape(len(differenced), m, s, 3), axis=1)
    return np.einsum("mji,dmsj->dmsi", lin.st_matrix, inertial)


def block_index(lin: Linearization, st_time, block_s) -> np.ndarray:
    """Block number of each whitened row (time-major, then set, then axis)."""
    blocks = np.floor((st_time - st_time[0]) / block_s).astype(int)
    per_time = lin.z.shape[1] * 3
    return np.repeat(blocks, per_time)
