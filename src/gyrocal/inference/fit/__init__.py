"""Deterministic fits of the channel model: the linearised likelihood, the noise scales' REML, the
full-trajectory weighted least squares, which parameters the data inform, and the paper's method."""

from gyrocal.inference.fit.classic import classic_start, classic_table
from gyrocal.inference.fit.estimate import PointEstimate, linearize_all, point_estimate
from gyrocal.inference.fit.identification import joint_information
from gyrocal.inference.fit.likelihood import campaign_stats

__all__ = [
    "PointEstimate", "campaign_stats", "classic_start", "classic_table", "joint_information", "linearize_all", "point_estimate",
]
