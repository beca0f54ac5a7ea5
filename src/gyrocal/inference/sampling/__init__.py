"""The posterior, sampled with emcee: the noise grid, the proposals, the budget that stops a chain
that will not converge, the posterior predictive and the InferenceData written from it."""

__all__ = ["budget", "inferencedata", "noisegrid", "posterior", "predictive", "proposal"]
