"""From a campaign's maneuvers to a posterior: preprocessing (eq. 4), the error model and its
noise, the likelihood, the paper's classic method, the point estimate and the emcee sampler."""

__all__ = [
    "calibration", "classic", "errormodel", "estimate", "identification", "inferencedata", "likelihood", "noise",
    "posterior", "predictive", "preprocess", "selectedinverse"
]
