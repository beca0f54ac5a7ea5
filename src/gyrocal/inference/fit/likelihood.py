"""The campaign likelihood, linear in the channel parameters about a linearisation point.

Per maneuver the differenced error series is ``D = X dtheta + G beta + noise`` with
``beta`` the nuisance (initial attitude error and the channel biases), given a flat
prior and integrated out exactly. What is left is quadratic in ``dtheta`` with
sufficient statistics ``A, b, c`` and a log determinant that depend only on the
noise variances; `Stats` holds them, summed over maneuvers.
"""

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from gyrocal.inference.noise.covariance import ManeuverNoise

__all__ = [
    "LOG_2PI", "Stats", "campaign_stats", "conditional_posterior", "leave_one_out_log_evidence", "log_evidence",
    "maneuver_stats", "total"
]

LOG_2PI = np.log(2 * np.pi)


@dataclass
class Stats:
    """``loglik(dtheta) = -(dtheta' A dtheta - 2 b' dtheta + c)/2 - logdet/2 - n log(2 pi)/2``."""

    A: np.ndarray
    b: np.ndarray
    c: float
    logdet: float
    n: int

    def loglik(self, dtheta: np.ndarray) -> np.ndarray:
        """Vectorised over the leading axis of ``dtheta``."""
        dtheta = np.atleast_2d(dtheta)
        quad = np.einsum("wi,ij,wj->w", dtheta, self.A, dtheta) - 2 * dtheta @ self.b + self.c
        return -0.5 * (quad + self.logdet + self.n * LOG_2PI)


def _logdet_chol(factor) -> float:
    return 2.0 * np.sum(np.log(np.diag(factor[0])))


def maneuver_stats(noise: ManeuverNoise, variances: dict) -> Stats:
    """One maneuver's `Stats` with the nuisance integrated out under a flat prior."""
    gram, logdet_c = noise.gram(variances)
    p, g = noise.n_params, noise.n_nuisance
    xs, gs = slice(0, p), slice(p, p + g)
    factor = cho_factor(gram[gs, gs])
    proj_x = cho_solve(factor, gram[gs, xs])
    proj_d = cho_solve(factor, gram[gs, -1])
    A = gram[xs, xs] - gram[xs, gs] @ proj_x
    b = gram[xs, -1] - gram[xs, gs] @ proj_d
    c = gram[-1, -1] - gram[-1, gs] @ proj_d
    return Stats(A, b, c, logdet_c + _logdet_chol(factor), noise.n - g)


def total(parts) -> Stats:
    """The `Stats` of independent parts of the data (maneuvers): their sum."""
    return Stats(sum(s.A for s in parts), sum(s.b for s in parts), sum(s.c for s in parts),
                 sum(s.logdet for s in parts), sum(s.n for s in parts))


def campaign_stats(noises, variances: dict) -> Stats:
    """Sum of `maneuver_stats` over the maneuvers (their noises are independent)."""
    return total([maneuver_stats(n, variances) for n in noises])


def conditional_posterior(stats: Stats, prior_mean, prior_sd):
    """Mean and covariance of ``dtheta`` given the noise: the exact Gaussian of the linear model."""
    prec = 1.0 / prior_sd**2
    P = stats.A + np.diag(prec)
    cov = np.linalg.inv(P)
    return cov @ (stats.b + prec * prior_mean), cov


def log_evidence(stats: Stats, prior_mean, prior_sd) -> float:
    """``log of the integral of N(dtheta; prior) exp(loglik(dtheta))``: the marginal likelihood of
    the data behind ``stats`` under independent normal priors (exact: the model is linear)."""
    prec = 1.0 / np.asarray(prior_sd, dtype=float) ** 2
    prior_mean = np.asarray(prior_mean, dtype=float)
    factor = cho_factor(stats.A + np.diag(prec))
    h = stats.b + prec * prior_mean
    return float(-0.5 * (stats.c + stats.logdet + stats.n * LOG_2PI)
                 + 0.5 * np.sum(np.log(prec)) - 0.5 * _logdet_chol(factor)
                 + 0.5 * h @ cho_solve(factor, h) - 0.5 * np.sum(prec * prior_mean**2))


def leave_one_out_log_evidence(parts, prior_mean, prior_sd) -> np.ndarray:
    """``log p(y_m | y_-m)`` for each part m (e.g. a maneuver) of data that are independent given
    the parameters: the exact predictive density after refitting without m, as the ratio of
    two evidences. ``parts`` are each part's `Stats` at the same noise variances."""
    whole = total(parts)
    full = log_evidence(whole, prior_mean, prior_sd)
    return np.array([full - log_evidence(Stats(whole.A - s.A, whole.b - s.b, whole.c - s.c,
                                                whole.logdet - s.logdet, whole.n - s.n), prior_mean, prior_sd)
                     for s in parts])
