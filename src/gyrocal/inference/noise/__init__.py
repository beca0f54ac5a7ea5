"""The noise of the attitude error: the star tracker's white and Gauss-Markov error and the gyro's
angle random walk as a banded covariance per maneuver, maneuvers chained where the reference's slow
error runs on, the smoothness a noise model can have, and the banded inverse's diagonal blocks."""

from gyrocal.inference.noise.covariance import ManeuverNoise, build, noise_knowledge, stated_scales, variances
from gyrocal.inference.noise.segments import chains
from gyrocal.inference.noise.smoothness import Smoothness

__all__ = ["ManeuverNoise", "Smoothness", "build", "chains", "noise_knowledge", "stated_scales", "variances"]
