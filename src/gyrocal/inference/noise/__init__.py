"""The noise of the attitude error: the star tracker's white and Gauss-Markov error and the gyro's
angle random walk as a banded covariance per maneuver, maneuvers chained where the reference's slow
error runs on, the smoothness a noise model can have, and the banded inverse's diagonal blocks."""

__all__ = ["covariance", "markov", "segments", "selectedinverse", "smoothness"]
