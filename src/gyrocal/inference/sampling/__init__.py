"""The posterior, sampled with emcee: the noise grid, the proposals, the budget that stops a chain
that will not converge, the posterior predictive and the InferenceData written from it."""

from gyrocal.inference.sampling.inferencedata import assemble
from gyrocal.inference.sampling.posterior import Posterior, Prepared, Priors, model_priors, prepare, run

__all__ = ["Posterior", "Prepared", "Priors", "assemble", "model_priors", "prepare", "run"]
