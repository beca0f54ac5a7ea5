"""The posterior, sampled with emcee: its priors, the noise grid, the proposals, the ensembles, the
budget that stops a chain that will not converge, the posterior predictive and the InferenceData written from it."""

from gyrocal.inference.sampling.inferencedata import assemble
from gyrocal.inference.sampling.posterior import Posterior, Prepared, prepare, run
from gyrocal.inference.sampling.priors import Priors, model_priors

__all__ = ["Posterior", "Prepared", "Priors", "assemble", "model_priors", "prepare", "run"]
