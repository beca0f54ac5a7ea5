"""The posterior of the channel parameters and the noise scales, sampled with emcee.

The error model is linearised about the WLS point estimate (see `errormodel`), the
nuisance is integrated out exactly (see `likelihood`), and what emcee samples is the
24 channel parameters (as offsets ``dtheta`` from the point estimate) and the three
noise scales ``log [sigma_cross, sigma_about, arw]``. The noise covariance is
``sigma_cross^2`` times a matrix fixed by two ratios; the scale enters in closed form
and the likelihood's sufficient statistics are tabulated on a grid over the ratios,
spanning many posterior standard deviations, and interpolated (cubic Lagrange). Given the
noise the posterior is Gaussian in ``dtheta``, so each move draws the noise and then
``dtheta`` from that conditional exactly (`CollapsedProposal`): only the noise is explored.

The priors come from `priors` (`model_priors`), the ensembles from `ensemble`; sampling comes in two
calls: `prepare` (the linearisation, the grid and the data's information, which a check can read) and `run`.
"""

from dataclasses import dataclass

import numpy as np

from gyrocal.inference.fit.estimate import linearize_all
from gyrocal.inference.fit.likelihood import (
    LOG_2PI,
    conditional_posterior,
    leave_one_out_log_evidence,
    maneuver_stats,
    total,
)
from gyrocal.inference.noise import segments
from gyrocal.inference.noise.covariance import noise_labels, noise_scales, ratios_of, variances
from gyrocal.inference.sampling.ensemble import SamplerResult, run_ensembles
from gyrocal.inference.sampling.noisegrid import NoiseShapes, RatioGrid, ratio_curvature
from gyrocal.inference.sampling.priors import GROUP_SD_PRIOR_LOG_SD, GROUP_SD_PRIOR_MEDIAN, Priors
from gyrocal.maneuvers.preprocess import noise_groups

__all__ = ["GROUP_SD_START_VARIANCE", "LogPosterior", "Posterior", "Prepared", "absolute", "leave_one_maneuver_out",
           "prepare", "run", "start_covariance"]


GROUP_SD_START_VARIANCE = 0.25
"""The start's variance of the log of that sd (few groups tell it to about half a unit)."""


class LogPosterior:
    """Vectorised log posterior of ``x = [dtheta (P), log sigma_cross, log sigma_about, log arw]``
    (and ``logit st_gm_fraction, log tau`` with correlated noise, then ``log sigma_t`` with the timing
    jitter: `covariance.noise_scales`).

    With noise groups, each group's own ``log sigma_cross`` and the log of their sd follow; the
    campaign's ``log sigma_cross`` is then their mean, and they are partially pooled about it
    (normal with that sd, a hierarchical prior), so a quiet group keeps its own level where its
    data tell it, and borrows the others' where not. Sampling the groups' levels themselves, which
    their data pin down, rather than their offsets from the mean, which only the prior separates
    from it, leaves no ridge for the chains to crawl along; for the same reason the about-boresight
    and ARW slots then hold their log ratios to the campaign's ``sigma_cross`` (`absolute`).
    """

    def __init__(self, grid: RatioGrid, theta_hat: np.ndarray, priors: Priors):
        self.grid = grid
        self.theta_hat = theta_hat
        self.priors = priors
        self.n_params = len(theta_hat)
        self.n_noise = len(priors.log_sigma_center)
        self.conditional_sd = priors.gaussian_sd(theta_hat)
        """The normal priors of the channel offsets' conditional (`conditional`): the priors' own where
        normal, a stand-in for a Student-t one (`Priors.gaussian_sd`); `__call__` has the exact density."""

    def conditional(self, noise_x, z=None):
        """The channel offsets' Gaussian conditional given the noise slots ``noise_x`` (W, dim - P), as its
        mean (W, P) and the lower Cholesky factor ``L`` of its precision (W, P, P), the bounds aside: the
        likelihood is Gaussian in ``dtheta`` at any noise, and so is its prior (`CollapsedProposal`).
        ``ok`` (W,) is False where that precision is not positive definite (far off the grid). Last, draws
        ``mean + L^-T z`` for standard normals ``z`` (W, P) (zeros: the mean), from the same solve as the
        mean (``L^-T z = (L L^T)^-1 L z``)."""
        k, pr = self.n_noise, self.priors
        log_sigma = noise_x[:, :k] if self.grid.n_groups == 1 else absolute(noise_x[:, :k])
        A, b = self.grid.stats(ratios_of(log_sigma))[:2]
        if self.grid.n_groups == 1:
            weight = np.exp(-2 * log_sigma[:, 0])
            precision, linear = A * weight[:, None, None], b * weight[:, None]
        else:
            weight = np.exp(-2 * noise_x[:, k:-1])
            precision, linear = np.einsum("wgij,wg->wij", A, weight), np.einsum("wgi,wg->wi", b, weight)
        sd = self.conditional_sd
        precision = precision + np.diag(sd**-2.0)
        linear = linear + (pr.mean - self.theta_hat) / sd**2
        precision = 0.5 * (precision + np.swapaxes(precision, 1, 2))
        ok = np.ones(len(precision), dtype=bool)
        try:
            chol = np.linalg.cholesky(precision)
        except np.linalg.LinAlgError:  # off the grid, extrapolated statistics may not be positive definite
            ok = np.all(np.linalg.eigvalsh(precision) > 0, axis=1)
            precision[~ok] = np.diag(sd**-2.0)
            chol = np.linalg.cholesky(precision)
        shift = np.zeros_like(linear) if z is None else np.einsum("wij,wj->wi", chol, z)
        both = np.linalg.solve(precision, np.stack([linear, linear + shift], axis=-1))
        return both[..., 0], chol, ok, both[..., 1]

    def __call__(self, x):
        x = np.atleast_2d(x)
        p, k = self.n_params, self.n_noise
        d, log_sigma = x[:, :p], x[:, p:p + k]
        if self.grid.n_groups > 1:  # the about and ARW slots hold their ratios to sigma_cross (`absolute`)
            log_sigma = absolute(log_sigma)
        A, b, c, logdet, inside = self.grid.stats(ratios_of(log_sigma))
        pr = self.priors
        if self.grid.n_groups == 1:
            scale = np.exp(2 * log_sigma[:, 0])
            quad = (d[:, None, :] @ A @ d[:, :, None])[:, 0, 0] - 2 * np.sum(b * d, axis=1) + c
            loglik = -0.5 * (quad / scale + logdet + self.grid.n * (np.log(scale) + LOG_2PI))
            logprior = 0.0
        else:
            levels, log_sd = x[:, p + k:-1], x[:, -1]  # each group's own log sigma_cross, what its data tell
            offsets = levels - log_sigma[:, :1]
            log_scale = 2 * levels
            quad = np.einsum("wi,wgij,wj->wg", d, A, d) - 2 * np.einsum("wgi,wi->wg", b, d) + c
            loglik = -0.5 * np.sum(quad * np.exp(-log_scale) + logdet + self.grid.n * (log_scale + LOG_2PI), axis=1)
            logprior = (-0.5 * np.sum(offsets**2, axis=1) * np.exp(-2 * log_sd) - offsets.shape[1] * log_sd
                        - 0.5 * ((log_sd - np.log(GROUP_SD_PRIOR_MEDIAN)) / GROUP_SD_PRIOR_LOG_SD) ** 2)
        theta = self.theta_hat + d
        logprior = logprior + pr.log_density(theta)
        logprior += pr.noise_log_density(log_sigma)
        ok = inside & np.all(np.abs(theta) <= pr.bound, axis=1)
        value = loglik + logprior
        return np.where(ok & np.isfinite(value), value, -np.inf)


def absolute(x):
    """Noise slots ``[log sigma_cross, log ratio about, log ratio ARW, ...]`` (with noise groups, as
    sampled) as log scales ``[log sigma_cross, log sigma_about, log arw, ...]``, on the last axis."""
    out = np.array(x, dtype=float, copy=True)
    out[..., 1:3] += out[..., :1]
    return out


def start_covariance(cond_cov, n_obs, ratio_sd):
    """Laplace covariance of ``[dtheta, log sigma_cross, log sigma_about, log arw]`` (and the model's
    other noise scales after them, `covariance.noise_scales`).

    ``log sigma_cross`` is known to about ``1/sqrt(2n)``; the other two are it plus the
    ratios, whose spread comes from the REML Hessian, as does the Gauss-Markov part's; give them
    the grid's `RatioGrid.sd`, capped where the grid's span is, so that the start lands on it
    (a Gauss-Markov share and tau the data hardly tell had a profile sd of 17 and 34 on RepoIMU,
    and 7 of 64 start points stayed off the grid after 100 redraws).
    """
    p, k = len(cond_cov), len(ratio_sd) + 1
    lift = np.eye(k)
    lift[1:3, 0] = 1.0
    hyper = lift @ np.diag(np.concatenate([[1.0 / (2 * n_obs)], np.asarray(ratio_sd) ** 2])) @ lift.T
    cov = np.zeros((p + k, p + k))
    cov[:p, :p] = cond_cov
    cov[p:, p:] = hyper
    return cov


@dataclass
class Posterior:
    """Everything the sampling step produces, before it is written out."""

    estimate: object
    lins: list
    noises: list
    grid: RatioGrid
    result: SamplerResult
    labels: list
    parts: list
    """Each maneuver's `likelihood.Stats` at the point estimate's noise scales."""
    group_index: np.ndarray | None = None
    """Each maneuver's noise group, where the campaign has more than one (`preprocess.noise_groups`)."""

    @property
    def n_params(self):
        return len(self.labels)

    def take_maneuvers(self):
        """Each maneuver's linearisation and noise structure, in order, each taken out of ``lins``
        and ``noises`` as it is handed on (both are empty after): a maneuver's noise (its banded
        covariance components and right-hand sides) is freed once its caller moves on, where the
        whole campaign's stayed until the step ended (0.4 GB on a campaign ten times the default).
        The point estimate's saved linearisations are these, so it lets go of them too (its
        `estimate.PointEstimate.linearize` computes one again if asked)."""
        self.estimate.at_estimate, self.estimate.at_estimate_keys = (), ()
        while self.noises:
            yield self.lins.pop(0), self.noises.pop(0)

    def ensemble_draws(self) -> np.ndarray:
        """(ensembles, steps * walkers, dim), step-major: split-R-hat across ensembles then
        compares early with late steps, so a drift after burn-in shows."""
        c = self.result.chains
        return c.reshape(c.shape[0], -1, c.shape[-1])

    def walker_draws(self) -> np.ndarray:
        """(ensembles * walkers, steps, dim): every walker a chain, so the ESS follows
        each walker's autocorrelation in time."""
        c = self.result.chains
        return np.transpose(c, (0, 2, 1, 3)).reshape(-1, c.shape[1], c.shape[-1])


def leave_one_maneuver_out(post: Posterior, priors: Priors) -> np.ndarray:
    """Exact ``log p(maneuver m | all others)`` per maneuver, the parameters refitted without it.

    The maneuvers are taken as independent given the parameters (each has its own nuisance; with
    correlated noise the posterior's grid chains them, `segments`, and this leaves that out), and the
    linearised model is Gaussian given the noise scales (held at the point estimate's), so each refit
    is a ratio of two closed-form evidences: no importance sampling.
    """
    return leave_one_out_log_evidence(post.parts, priors.mean - post.estimate.theta,
                                      priors.gaussian_sd(post.estimate.theta))


@dataclass
class Prepared:
    """What `prepare` computes at the point estimate before a step is taken, and `run` samples from.
    ``stats`` and ``ratio_sd`` (the data's information, the nuisance integrated out, and the noise
    ratios' spread) are what a check of identification reads before the sampler runs."""

    estimate: object
    priors: Priors
    lins: list
    noises: list
    grid: RatioGrid
    logpost: LogPosterior
    parts: list
    """Each maneuver's `likelihood.Stats` at the point estimate's noise scales."""
    stats: object
    """The campaign's `likelihood.Stats` at the fitted noise (with correlated noise, the maneuvers chained)."""
    ratio_sd: np.ndarray
    """The noise ratios' sds from the REML profile's Hessian (their prior's where it is flat: `ratio_curvature`)."""
    group_index: np.ndarray | None = None
    """Each maneuver's noise group, where the campaign has more than one (`preprocess.noise_groups`)."""

    @property
    def labels(self) -> list:
        """The sampled dimensions' names, in the order of the log posterior's ``x`` (`LogPosterior`)."""
        est = self.estimate
        labels = list(est.spec.labels) + noise_labels(est.spec.correlated_noise, est.spec.jitter_noise)
        if self.group_index is not None:
            labels += [f"noise.level.{g}" for g in est.noise_groups] + ["noise.group_sd"]
        return labels


def prepare(maneuvers, estimate, priors: Priors, grid_cfg: dict) -> Prepared:
    """Linearise about the point estimate, tabulate the noise ratios on their grid and gather the data's
    information at the fitted noise: everything the sampler needs, and what is checked before it runs."""
    lins, noises = linearize_all(maneuvers, estimate)
    spec = estimate.spec
    ratios = ratios_of(estimate.log_sigma)
    index = noise_groups(maneuvers)[1] if estimate.group_offsets is not None else None
    shapes = NoiseShapes(noises, groups=index)
    if spec.correlated_noise:
        shapes = NoiseShapes(noises, lins, estimate.boresight, index, segments.Chains.of(maneuvers), spec.jitter_noise)
    ratio_sd = ratio_curvature(shapes, ratios, priors.ratio_sd(noise_scales(spec.correlated_noise, spec.jitter_noise)))
    grid = RatioGrid(shapes, ratios, ratio_sd, grid_cfg["nodes"], grid_cfg["half_width_sd"])
    logpost = LogPosterior(grid, estimate.theta, priors)
    if index is None:
        parts = [maneuver_stats(nz, variances(estimate.log_sigma)) for nz in noises]
    else:
        parts = [maneuver_stats(nz, estimate.maneuver_variances(m, g)) for m, (nz, g) in enumerate(zip(noises, index))]
    if shapes.correlated:  # the information the posterior has: the maneuvers chained (`segments`)
        levels = np.zeros(len(shapes.chained.members), dtype=int) if index is None else shapes.groups_of_parts
        stats = total([maneuver_stats(nz, estimate.maneuver_variances(0, g)) for nz, g in zip(shapes.at(ratios), levels)])
    else:
        stats = total(parts)
    return Prepared(estimate, priors, lins, noises, grid, logpost, parts, stats, ratio_sd, index)


def run(ready: Prepared, sampler_cfg: dict, seed: int) -> Posterior:
    """Start at the Laplace approximation about the conditional posterior and run the ensembles
    (`run_ensembles`; `budget.SamplingStopped` where the budget cannot converge)."""
    estimate, priors, grid, stats, index = ready.estimate, ready.priors, ready.grid, ready.stats, ready.group_index
    mean, cov = conditional_posterior(stats, priors.mean - estimate.theta, priors.gaussian_sd(estimate.theta))
    start_mean = np.concatenate([mean, estimate.log_sigma])
    start_cov = start_covariance(cov, stats.n, grid.sd)
    if index is not None:
        offsets, p, k = estimate.group_offsets, len(mean), len(estimate.log_sigma)
        start_mean[p + 1:p + 3] -= start_mean[p]
        start_cov[p:, p:] = np.diag(np.concatenate([[GROUP_SD_START_VARIANCE], np.asarray(grid.sd) ** 2]))
        start_mean = np.concatenate([start_mean, estimate.log_sigma[0] + offsets, [np.log(max(np.std(offsets), 0.1))]])
        spread = np.concatenate([0.5 / np.asarray(grid.n, dtype=float), [GROUP_SD_START_VARIANCE]])
        start_cov = np.block([[start_cov, np.zeros((len(start_cov), len(spread)))],
                              [np.zeros((len(spread), len(start_cov))), np.diag(spread)]])
    result = run_ensembles(ready.logpost, start_mean, start_cov, sampler_cfg, seed)
    if index is not None:  # every later step reads log scales
        result.chains[..., p:p + k] = absolute(result.chains[..., p:p + k])
    return Posterior(estimate, ready.lins, ready.noises, grid, result, list(estimate.spec.labels), ready.parts, index)
