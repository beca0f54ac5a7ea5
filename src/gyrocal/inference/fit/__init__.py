"""Deterministic fits of the channel model: the linearised likelihood, the noise scales' REML, the
full-trajectory weighted least squares, which parameters the data inform, and the paper's method."""

__all__ = ["classic", "estimate", "identification", "likelihood", "noisefit", "trustregion"]
