"""The posterior, sampled with emcee: its priors, the noise grid, the proposals, the ensembles, the
budget that stops a chain that will not converge, the refusals before sampling,
the posterior predictive and the InferenceData written from it.

Its entry points, below, are imported when first asked for (`gyrocal.exports`): a step that needs one
of its modules (the diagnostics' `predictive`) does not import arviz and emcee with it (1.5-2 s of CPU
per job)."""

from gyrocal.exports import lazy

_ENTRY_POINTS = {"model_priors": "priors", "Priors": "priors", "prepare": "posterior", "run": "posterior",
                 "Prepared": "posterior", "Posterior": "posterior", "assemble": "inferencedata"}
"""Each entry point and the module it comes from."""

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy(__name__, _ENTRY_POINTS)
