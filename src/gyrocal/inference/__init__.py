"""From a campaign's maneuvers to a posterior, in three families, each a package: the noise model
(`noise`), the deterministic fits (`fit`) and the sampler (`sampling`), above the error model and
its Jacobian (`errormodel`); `interval` chooses the reference interval with a pilot fit."""

__all__ = ["errormodel", "fit", "interval", "noise", "sampling"]
