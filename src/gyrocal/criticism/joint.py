"""One calibration from several campaigns of one unit: a joint fit of the shared channel parameters.

Each campaign's likelihood of its parameters is Gaussian about its point estimate (the WLS, no
prior) with the information ``I = cov^-1`` at its own REML noise: the linear model of
`gyrocal.inference.fit.likelihood` with the nuisance (initial attitude error, biases of each
maneuver) integrated out. The campaign's own parameters beyond the channel model (a bias drift,
a latency) are integrated out too, under their prior (`CampaignLikelihood.of`). The shared
channel parameters then combine by summing information, and the prior enters once:

    P = sum_k I_k + diag(1 / prior_sd^2),   mean = P^-1 (sum_k I_k x_k + prior_mean / prior_sd^2).

So each campaign keeps its own bias, noise and mounting, and the intervals shrink as campaigns are
added (two of one design: by 1/sqrt 2). Before they are summed, each campaign is turned into the
first one's body frame (`gyrocal.criticism.agreement.into_frame`, linearised at its estimate) where
the runs aligned their references differently.
"""

from dataclasses import dataclass

import numpy as np
import pandas as pd

from gyrocal.criticism.agreement import into_frame
from gyrocal.io.calibration import COLUMNS
from gyrocal.model.spec import ModelSpec

__all__ = ["CampaignLikelihood", "JointFit", "joint_fit", "joint_table"]

_STEP = 1e-3
"""Finite-difference step of the frame turn's Jacobian, in the parameters' units (ppm, arcsec)."""


@dataclass
class CampaignLikelihood:
    """One campaign's Gaussian likelihood of the channel model's terms (SI, the spec's core order)."""

    name: str
    labels: list
    estimate: np.ndarray
    """The point estimate; 0 where the campaign says nothing (its information there is 0)."""
    info: np.ndarray
    free: np.ndarray | None = None
    """The parameters this campaign informs (not prior-only in its run); None: where ``info`` is not zero."""

    def __post_init__(self):
        if self.free is None:
            self.free = np.diag(self.info) > 0

    @classmethod
    def of(cls, name: str, spec: ModelSpec, theta, cov, prior_mean, prior_sd) -> "CampaignLikelihood":
        """From a point estimate (``theta``, its covariance ``cov`` with NaN rows where prior-only),
        the parameters beyond the channel model integrated out under their prior (``prior_mean``,
        ``prior_sd``: SI, every parameter of ``spec``)."""
        free = spec.free
        core = np.zeros(len(spec), dtype=bool)
        core[spec.core] = True
        info = np.zeros((len(spec), len(spec)))
        info[np.ix_(free, free)] = np.linalg.inv(np.asarray(cov)[np.ix_(free, free)])
        x = np.where(free, theta, 0.0)
        h = info @ x
        c, e = core, ~core
        if e.any():
            own = info[np.ix_(e, e)] + np.diag(1.0 / np.asarray(prior_sd)[e] ** 2)
            gain = info[np.ix_(c, e)] @ np.linalg.inv(own)
            info_c = info[np.ix_(c, c)] - gain @ info[np.ix_(e, c)]
            h_c = h[c] - gain @ (h[e] + np.asarray(prior_mean)[e] / np.asarray(prior_sd)[e] ** 2)
        else:
            info_c, h_c = info, h
        informed = np.diag(info_c) > 0
        estimate = np.zeros(int(c.sum()))
        estimate[informed] = np.linalg.solve(info_c[np.ix_(informed, informed)], h_c[informed])
        return cls(name, list(spec.labels[spec.core]), estimate, 0.5 * (info_c + info_c.T), free[spec.core])

    def turned(self, spec: ModelSpec, turn) -> "CampaignLikelihood":
        """This likelihood in another body frame (``turn``, a scipy Rotation taking this run's body
        axes into the other's): the estimate mapped exactly, the information through the map's
        Jacobian at the estimate (``I' = J^-T I J^-1``)."""
        if turn is None or turn.magnitude() == 0:
            return self
        units = np.asarray(spec.si_per_unit)[spec.core]
        params = list(spec.parameters[spec.core])
        table = pd.DataFrame({"channel": [p.owner for p in params], "parameter": [p.name for p in params]})

        def mapped(x_units):
            return into_frame(table.assign(mean=x_units), turn)["mean"].to_numpy()

        x = self.estimate / units
        jac = np.empty((len(x), len(x)))
        for j in range(len(x)):
            step = np.zeros(len(x))
            step[j] = _STEP
            jac[:, j] = (mapped(x + step) - mapped(x - step)) / (2 * _STEP)
        inv = np.linalg.inv(jac)
        info_units = self.info * np.outer(units, units)
        info = inv.T @ info_units @ inv / np.outer(units, units)
        return CampaignLikelihood(self.name, self.labels, mapped(x) * units, 0.5 * (info + info.T), self.free)


@dataclass
class JointFit:
    """The joint Gaussian posterior of the shared channel parameters (SI)."""

    labels: list
    mean: np.ndarray
    cov: np.ndarray
    point: np.ndarray
    """The campaigns' joint likelihood maximum, with the prior only on what no campaign informs."""
    informed: np.ndarray
    """The parameters some campaign informs (the others are prior-only in every run)."""

    @property
    def sd(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov))


def joint_fit(likelihoods, prior_mean, prior_sd) -> JointFit:
    """Sum the campaigns' information and add the prior once (SI, the channel model's terms)."""
    prior_mean, prior_sd = np.asarray(prior_mean, dtype=float), np.asarray(prior_sd, dtype=float)
    info = sum(lik.info for lik in likelihoods)
    h = sum(lik.info @ lik.estimate for lik in likelihoods)
    cov = np.linalg.inv(info + np.diag(1.0 / prior_sd**2))
    informed = np.any([lik.free for lik in likelihoods], axis=0)
    held = np.where(informed, 0.0, 1.0 / prior_sd**2)  # the prior only where no campaign informs
    point = np.linalg.solve(info + np.diag(held), h + held * prior_mean)
    return JointFit(likelihoods[0].labels, cov @ (h + prior_mean / prior_sd**2), 0.5 * (cov + cov.T), point, informed)


def joint_table(spec: ModelSpec, fit: JointFit) -> pd.DataFrame:
    """``calibration.csv``'s columns (docs/interface.md section 5) for the joint fit: a Gaussian, so
    the interval is mean +- 1.96 sd and there is no sampler (``r_hat``, ``ess_bulk`` empty)."""
    units = np.asarray(spec.si_per_unit)[spec.core]
    mean, sd, point = fit.mean / units, fit.sd / units, fit.point / units
    params = spec.parameters[spec.core]
    return pd.DataFrame({"channel": [p.owner for p in params], "parameter": [p.name for p in params],
                         "unit": [p.unit for p in params], "point": point, "mean": mean, "sd": sd,
                         "ci95_low": mean - 1.959964 * sd, "ci95_high": mean + 1.959964 * sd,
                         "r_hat": np.nan, "ess_bulk": np.nan, "prior_only": ~fit.informed}, columns=COLUMNS)
