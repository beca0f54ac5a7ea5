"""The ensemble sampler: independent emcee ensembles with the collapsed move, run until every chain is
long against its autocorrelation time, or stopped with the reason once the budget cannot get there."""

import logging
from dataclasses import dataclass

import arviz as az
import emcee
import numpy as np

from gyrocal.inference.sampling.budget import SamplingBudget
from gyrocal.inference.sampling.proposal import (
    CollapsedProposal,
    ConditionalCache,
    SamplingError,
    StudentProposal,
    fitted_noise_proposal,
)

__all__ = ["AUTOCORR_WINDOW_C", "DE_SHARE", "LOCAL_SCALE", "LOCAL_SHARE", "MAX_REFITS", "REFIT_MAX_STEPS",
           "REFIT_MIN_STEPS", "REFIT_TAU_STEPS", "START_REDRAWS", "SamplerResult", "run_ensembles"]


@dataclass
class SamplerResult:
    chains: np.ndarray
    """(ensembles, steps, walkers, dim) production samples."""
    tau: np.ndarray
    """(ensembles, dim) integrated autocorrelation times, in steps."""
    steps: int
    burn: int
    acceptance: np.ndarray
    converged_length: bool
    walkers: int
    refits: int = 0
    """Times the noise proposal was refitted before the kept production (`REFIT_TAU_STEPS`)."""


AUTOCORR_WINDOW_C = 5.0
"""Sokal's window constant, emcee's default for `emcee.autocorr.integrated_time`."""


def _autocorr_times(chain) -> np.ndarray:
    """emcee's integrated autocorrelation time per parameter of a (steps, walkers, dim) chain
    (`emcee.autocorr.integrated_time`): the walkers' mean autocorrelation and Sokal's window, with
    every walker and parameter in one FFT (`arviz.autocorr`) where emcee takes one at a time
    (eight times as fast, the same times to 1e-15). A walker that never moves leaves its
    parameter's time undefined (NaN), as in emcee. The caller compares the length with them."""
    rho = az.autocorr(np.moveaxis(chain, 0, -1), axis=-1).mean(axis=0)
    taus = 2.0 * np.cumsum(rho, axis=-1) - 1.0
    tau = taus[np.arange(len(taus)), _sokal_window(taus, AUTOCORR_WINDOW_C)]
    tau[np.any(np.ptp(chain, axis=0) == 0, axis=0)] = np.nan
    return tau


def _sokal_window(taus, c: float) -> np.ndarray:
    """Each row's window: the first lag M with ``M >= c * tau(M)`` (lag 0 where no lag reaches it, as emcee's
    argmin gives). emcee's ``auto_window`` (emcee 3.1, MIT licence, D. Foreman-Mackey and contributors)
    over every row at once: it is not in ``emcee.autocorr.__all__``; tests/test_numerics.py pins the
    times against `emcee.autocorr.integrated_time`."""
    below = np.arange(taus.shape[-1]) < c * taus
    return np.where(below.any(axis=-1), np.argmin(below, axis=-1), taus.shape[-1] - 1)


DE_SHARE = 0.1
LOCAL_SHARE = 0.2
LOCAL_SCALE = 2.38
"""Shares of differential-evolution moves and of the collapsed move's local steps (a random walk in the
noise, ``LOCAL_SCALE / sqrt(k)`` times the fitted proposal's scale in k slots): they keep a walker moving
where the independence proposal falls short (a misfit model, a ratio at its grid's edge, GM share and tau)."""


def _sampler(logpost, walkers, dim, noise, seed):
    """An emcee sampler with its own random state, seeded: numpy's global state is untouched. Moves: the
    collapsed move about ``noise`` (`CollapsedProposal`), independent and local (`LOCAL_SHARE`), and DE."""
    p = logpost.n_params
    shared = ConditionalCache(logpost.conditional)
    local = CollapsedProposal(shared, p, noise, LOCAL_SCALE / np.sqrt(dim - p))
    moves = [(emcee.moves.MHMove(CollapsedProposal(shared, p, noise)), 1.0 - DE_SHARE - LOCAL_SHARE),
             (emcee.moves.MHMove(local), LOCAL_SHARE), (emcee.moves.DEMove(), DE_SHARE)]
    sampler = emcee.EnsembleSampler(walkers, dim, logpost, vectorize=True, moves=moves)
    sampler.random_state = np.random.RandomState(seed).get_state()
    return sampler


START_REDRAWS = 100
"""Start points with zero posterior density are redrawn at most this often, then sampling stops."""

REFIT_TAU_STEPS = 20.0
"""A production chain whose autocorrelation time exceeds this many steps (the default campaign's are
2.4-2.9) mixes slowly because its noise proposal, fitted to a burn-in too short for it, misses part
of the posterior: the proposal is refitted to the second half of the chain so far, and production
starts again from where the walkers are, what came before counted as burn-in (`MAX_REFITS` times).
The production kept is a chain of a fixed kernel; the steps discarded count against the budget."""
MAX_REFITS = 2
REFIT_MIN_STEPS = 250
"""A refit waits for this many production steps, whose second half it is fitted to..."""
REFIT_MAX_STEPS = 500
"""...and comes no later than this: a chain slow after that is left to the budget, so refits discard
at most ``MAX_REFITS * REFIT_MAX_STEPS`` steps."""

log = logging.getLogger("gyrocal")


def run_ensembles(logpost, proposal_mean, proposal_cov, cfg: dict, seed: int) -> SamplerResult:
    """Independent emcee ensembles of the log posterior ``logpost`` (`posterior.LogPosterior`), run until
    every chain is k autocorrelation times long, or stopped (`budget.SamplingStopped`: the reason, the
    times) once the budget cannot get there (`SamplingBudget`). Moves:
    the collapsed move (`CollapsedProposal`: the noise from an independence proposal, the channel offsets from
    their exact conditional) and differential evolution (`DE_SHARE`). Each ensemble burns in from the Laplace
    approximation's noise block, fits its own noise proposal (`fitted_noise_proposal`) twice and keeps it for
    production, so the ensembles stay independent; ensemble e's samplers and start points have seeds of their own."""
    dim, budget = len(proposal_mean), SamplingBudget(cfg)  # its clock counts the burn-in
    walkers = max(int(cfg["walkers"]), 2 * dim + 2)
    walkers += walkers % 2
    n_ens, burn = int(cfg["ensembles"]), int(cfg["burn_steps"])
    chunk, multiple, max_steps = int(cfg["chunk_steps"]), float(cfg["min_tau_multiple"]), int(cfg["max_steps"])
    laplace = StudentProposal(proposal_mean, proposal_cov)
    start = StudentProposal(proposal_mean, proposal_cov, dof=5.0, inflate=2.0)
    samplers, seeds = [], []
    for e in range(n_ens):
        sampler_seed = (seed * 7919 + e) % 2**32
        seeds.append(sampler_seed)
        rng = np.random.default_rng([seed, e])
        p0 = start.draw(rng.standard_normal((walkers, dim)), rng.chisquare(start.dof, walkers))
        bad = ~np.isfinite(logpost(p0))
        for _ in range(START_REDRAWS):
            if not bad.any():
                break
            p0[bad] = laplace.draw(rng.standard_normal((bad.sum(), dim)), rng.chisquare(laplace.dof, bad.sum()))
            bad = ~np.isfinite(logpost(p0))
        if bad.any():
            valid = getattr(getattr(logpost, "grid", None), "valid", None)
            unfactored = ("" if valid is None or valid.all() else f"; the noise's covariance is not positive definite at "
                          f"{(~valid).sum()} of {valid.size} of the grid's nodes, which leaves little of it")
            raise SamplingError(f"posterior: after {START_REDRAWS} redraws, {bad.sum()} of {walkers} start points of "
                                f"ensemble {e} still have zero posterior density (outside the physical bounds or the "
                                f"noise-ratio grid{unfactored}): the point estimate is not a usable start")
        p = logpost.n_params
        noise, state = StudentProposal(proposal_mean[p:], proposal_cov[p:, p:]), p0
        for _ in range(2):
            warm = _sampler(logpost, walkers, dim, noise, sampler_seed)
            state = warm.run_mcmc(state, burn // 2)
            noise = fitted_noise_proposal(warm.get_chain(discard=burn // 4, flat=True)[:, p:])
        samplers.append([_sampler(logpost, walkers, dim, noise, sampler_seed), state])
    steps, refits, spent = 0, 0, 0
    while True:
        n_new = int(cfg["initial_steps"]) if steps == 0 else chunk
        for pair in samplers:
            pair[1] = pair[0].run_mcmc(pair[1], n_new)
        steps += n_new
        tau = np.array([_autocorr_times(s.get_chain()) for s, _ in samplers])
        if steps >= multiple * tau.max() or spent + steps + chunk > max_steps:
            break
        if (refits < MAX_REFITS and REFIT_MIN_STEPS <= steps <= REFIT_MAX_STEPS and np.nanmax(tau) > REFIT_TAU_STEPS
                and (refitted := _refitted(samplers, logpost, walkers, dim, seeds, steps // 2))):
            samplers, refits = refitted, refits + 1
            log.info("posterior: autocorrelation time %.1f steps after %d: the noise proposal refitted to the "
                     "chains' second half (refit %d of at most %d), production starts again", np.nanmax(tau), steps,
                     refits, MAX_REFITS)
            burn, spent, steps = burn + steps, spent + steps, 0
            continue
        budget.check(steps, tau, spent)
    chains = np.stack([s.get_chain() for s, _ in samplers])
    acceptance = np.array([s.acceptance_fraction.mean() for s, _ in samplers])
    return SamplerResult(chains, tau, steps, burn, acceptance, bool(steps >= multiple * tau.max()), walkers, refits)


def _refitted(samplers, logpost, walkers, dim, seeds, discard):
    """Each ensemble's sampler with its noise proposal fitted to its chain after ``discard`` steps, at
    the walkers' states; None where a chain's noise did not move there (the budget then says why).
    The states carry each ensemble's random state on, so the streams stay the ensembles' own."""
    p = logpost.n_params
    try:
        proposals = [fitted_noise_proposal(s.get_chain(discard=discard, flat=True)[:, p:]) for s, _ in samplers]
    except SamplingError:
        return None
    return [[_sampler(logpost, walkers, dim, noise, seeds[e]), state]
            for e, (noise, (_, state)) in enumerate(zip(proposals, samplers))]
