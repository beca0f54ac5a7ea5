"""From a campaign's maneuvers to a posterior, in three families, each a package: the noise model
(`noise`), the deterministic fits (`fit`) and the sampler (`sampling`), above the error model and
its Jacobian (`errormodel`); `interval` chooses the reference interval with a pilot fit."""

from gyrocal.inference.errormodel import Linearization, linearize
from gyrocal.inference.interval import choose

__all__ = ["Linearization", "choose", "linearize"]
