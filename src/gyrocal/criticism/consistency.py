"""Are several campaigns of one unit consistent with one calibration? A multivariate chi-square test.

Two campaigns' posteriors of the shared channel parameters, means ``m_A, m_B`` and covariances
``C_A, C_B``, differ by ``d = m_B - m_A``; under one calibration ``d' (C_A + C_B)^-1 d`` is
chi-square with as many degrees of freedom as directions compared. Parameter by parameter z
scores ignore the correlations (a misalignment's error shared with the attitude, the two scale
factors of one channel) and make no test with a stated level; this does.

**The prior's directions.** Where the data say little, both posteriors are the prior and their
difference says nothing. In coordinates whitened by the prior sd, the prior's covariance of the
difference is ``2 I``, so the eigen-directions of ``C_A + C_B`` there are also those of its ratio to
the prior's: an eigenvalue ``2 s`` means the posteriors keep a share ``s`` of the prior's variance
along it. Directions with ``s > PRIOR_SHARE_MAX`` are left out of the test (and of its degrees of
freedom); a parameter prior-only in either campaign (``s >= 1/2`` along it) is always left out.
Along the directions kept the prior pulls each mean by at most that share, so the test is exact
where the data dominate and conservative by at most the share elsewhere.

**More than two campaigns.** Each is tested against the joint posterior of the others (their
information summed, the prior once), and the campaigns are called consistent when every such test
passes at the level divided by their number (Bonferroni: the stated level holds).
"""

from dataclasses import dataclass

import numpy as np
from scipy import stats

__all__ = ["PRIOR_SHARE_MAX", "Consistency", "Direction", "consistency", "pair_test", "posterior_of"]

PRIOR_SHARE_MAX = 0.1
"""A direction is compared when the posteriors keep at most this share of the prior's variance of
the difference along it: the data carry at least nine times the prior's information there."""


def posterior_of(estimate, info, prior_mean, prior_sd):
    """The Gaussian posterior (mean, covariance) from a likelihood's estimate and information and
    independent normal priors (all SI); NaN estimates (no information) count as zero."""
    return _posterior(info @ np.nan_to_num(np.asarray(estimate, dtype=float)), info, prior_mean, prior_sd)


def _posterior(h, info, prior_mean, prior_sd):
    prec = 1.0 / np.asarray(prior_sd, dtype=float) ** 2
    cov = np.linalg.inv(info + np.diag(prec))
    cov = 0.5 * (cov + cov.T)
    return cov @ (h + prec * prior_mean), cov


@dataclass
class Direction:
    """One eigen-direction of the difference's covariance, and its share of chi-square."""

    chi2: float
    """``z^2`` of the difference along the direction."""
    z: float
    loadings: dict
    """label: weight, the direction in prior-sd units (unit length), the largest first (|w| >= 0.1)."""


def pair_test(mean_a, cov_a, mean_b, cov_b, prior_sd, labels, share_max: float = PRIOR_SHARE_MAX,
              top: int = 3) -> dict:
    """``d' (C_A + C_B)^-1 d`` over the directions the data inform (SI inputs): ``chi2``, ``dof``,
    ``p_value`` and the ``top`` eigen-directions that contribute most (`Direction`)."""
    prior_sd = np.asarray(prior_sd, dtype=float)
    d = (np.asarray(mean_b) - np.asarray(mean_a)) / prior_sd
    total = (np.asarray(cov_a) + np.asarray(cov_b)) / np.outer(prior_sd, prior_sd)
    values, vectors = np.linalg.eigh(0.5 * (total + total.T))
    keep = values <= 2.0 * share_max
    along = vectors[:, keep].T @ d
    z = along / np.sqrt(values[keep])
    order = np.argsort(z**2)[::-1][:top]
    directions = []
    for i in order:
        v = vectors[:, keep][:, i]
        sign = np.sign(v[np.argmax(np.abs(v))])
        big = np.argsort(np.abs(v))[::-1]
        directions.append(Direction(float(z[i] ** 2), float(sign * z[i]),
                                    {labels[j]: float(sign * v[j]) for j in big if abs(v[j]) >= 0.1}))
    chi2, dof = float(np.sum(z**2)), int(keep.sum())
    return {"chi2": chi2, "dof": dof, "p_value": float(stats.chi2.sf(chi2, dof)) if dof else 1.0,
            "directions": directions}


@dataclass
class Consistency:
    """The test of several campaigns against one calibration."""

    chi2: float
    dof: int
    p_value: float
    """For two campaigns, the pair's; for more, the smallest of the `against_rest` tests' times
    their number (at most 1)."""
    against_rest: list
    """Per campaign (its index, ``campaign``), the `pair_test` of the others' joint posterior against its
    own; for two campaigns only the second's (``d = m_B - m_A``)."""

    def consistent(self, level: float) -> bool:
        return bool(self.p_value >= level)


def consistency(estimates, infos, prior_mean, prior_sd, labels, share_max: float = PRIOR_SHARE_MAX,
                top: int = 3) -> Consistency:
    """The test of campaigns whose likelihoods of the same parameters ``labels`` have estimates
    ``estimates[k]`` and information ``infos[k]`` (SI), under independent normal priors."""
    prior_mean = np.asarray(prior_mean, dtype=float)
    estimates = [np.nan_to_num(np.asarray(x, dtype=float)) for x in estimates]
    infos = [np.nan_to_num(np.asarray(i, dtype=float)) for i in infos]
    total_info, total_h = sum(infos), sum(i @ x for i, x in zip(infos, estimates))
    rest = []
    for k in [1] if len(infos) == 2 else range(len(infos)):  # two: B against A, d = m_B - m_A
        x, info = estimates[k], infos[k]
        own = posterior_of(x, info, prior_mean, prior_sd)
        others = _posterior(total_h - info @ x, total_info - info, prior_mean, prior_sd)
        rest.append({"campaign": k, **pair_test(*others, *own, prior_sd, labels, share_max, top)})
    if len(rest) == 1:
        return Consistency(rest[0]["chi2"], rest[0]["dof"], rest[0]["p_value"], rest)
    worst = min(rest, key=lambda t: t["p_value"])
    return Consistency(worst["chi2"], worst["dof"], min(1.0, worst["p_value"] * len(rest)), rest)
