"""The posterior, sampled with emcee: the noise grid, the proposals, the budget that stops a chain
that will not converge, the posterior predictive and the InferenceData written from it.

The names below are imported when first asked for, not with the package: a step that needs one
module of it (the diagnostics' `predictive`, the point estimate's nothing) does not import arviz and
emcee (1.5-2 s of CPU per job)."""

import importlib

__all__ = ["Posterior", "Prepared", "Priors", "assemble", "model_priors", "prepare", "run"]

_FROM = {"assemble": "inferencedata", **{name: "posterior" for name in __all__ if name != "assemble"}}


def __getattr__(name):
    if name in _FROM:
        return getattr(importlib.import_module(f"{__name__}.{_FROM[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
