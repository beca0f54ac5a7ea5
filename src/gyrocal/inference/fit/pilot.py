"""The pilot fit: the baseline channel model (scale factors, misalignments, biases) fitted with its noise
scales estimated, the same for every model variant of a run, so that what the preprocessing chooses from
it (the reference interval, `gyrocal.inference.interval`; the reference error's clock,
`gyrocal.inference.clock`) holds for their comparison."""

from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import point_estimate
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec

__all__ = ["pilot"]


def pilot(maneuvers, stated_noise: dict, sensor_class=None):
    """The baseline channel model's point estimate (its noise scales estimated, as every model's are:
    a stated ARW far below the data's would leave the walk's interpolation shortfall, `smoothness`,
    too small), and each maneuver's linearisation about it."""
    fx = effects.resolve("baseline", effects.BASELINE, {})
    spec = ModelSpec.build("pilot", fx, maneuvers[0].channels).with_sensor_class(sensor_class)
    est = point_estimate(maneuvers, spec, stated_noise, classic.classic_start(maneuvers, spec))
    return est, [est.linearize(maneuvers, m) for m in range(len(maneuvers))]
