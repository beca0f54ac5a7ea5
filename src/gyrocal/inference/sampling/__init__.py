"""The posterior, sampled with emcee: its priors, the noise grid, the proposals, the ensembles, the
budget that stops a chain that will not converge, the refusals before sampling,
the posterior predictive and the InferenceData written from it.

The package imports none of its modules itself: a step that needs one of them (the diagnostics'
`predictive`) does not import arviz and emcee with it (1.5-2 s of CPU per job). The names it used to
take from them (`assemble`, `Posterior`, `Prepared`, `Priors`, `model_priors`, `prepare`, `run`) are
still there, imported when first asked for."""

import importlib

__all__ = ["budget", "ensemble", "inferencedata", "noisegrid", "posterior", "predictive", "priors", "proposal", "refusals"]

_FROM = {"assemble": "inferencedata", "Posterior": "posterior", "Prepared": "posterior", "prepare": "posterior",
         "run": "posterior", "Priors": "priors", "model_priors": "priors"}


def __getattr__(name):
    if name in _FROM:
        return getattr(importlib.import_module(f"{__name__}.{_FROM[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
