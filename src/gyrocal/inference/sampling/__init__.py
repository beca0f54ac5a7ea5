"""The posterior, sampled with emcee: its priors, the noise grid, the proposals, the ensembles, the
budget that stops a chain that will not converge, the posterior predictive and the InferenceData written from it.

The names below are imported when first asked for, not with the package: a step that needs one
module of it (the diagnostics' `predictive`, the point estimate's nothing) does not import arviz and
emcee (1.5-2 s of CPU per job)."""

import importlib

__all__ = ["Posterior", "Prepared", "Priors", "assemble", "model_priors", "prepare", "run"]

_FROM = {"assemble": "inferencedata", "Posterior": "posterior", "Prepared": "posterior", "prepare": "posterior",
         "run": "posterior", "Priors": "priors", "model_priors": "priors"}


def __getattr__(name):
    if name in _FROM:
        return getattr(importlib.import_module(f"{__name__}.{_FROM[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
