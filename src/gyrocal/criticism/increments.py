"""The residual's increments against the noise model's reach: a residual smooth at the sampling
interval (`gyrocal.inference.noise.smoothness`) is structure no noise model here can represent, so its
intervals would rest on a wrong likelihood."""

from gyrocal.finding import Finding
from gyrocal.inference.noise import smoothness

__all__ = ["smoothness_finding"]


def smoothness_finding(measured) -> Finding:
    """Passes where no maneuver's residual (``measured``: `smoothness.of_maneuver` of each) grows faster
    with the lag than white noise, the gyro's walk and a Gauss-Markov part can; else names them and
    the reference interval to use."""
    words = smoothness.describe(measured)
    first = [float(s.exponent[0]) for s in measured if len(s.exponent)]
    return Finding.judged(
        "smoothness", not words,
        words or "the residual's increments grow with the lag no faster than the noise model allows "
                 "(at most as its square root) at the sampling interval",
        figure=max(first, default=None), threshold=smoothness.MODEL_EXPONENT_MAX, unit="growth exponent",
        action=f"--config reference_interval_s={smoothness.recommended_interval_s(measured):.3g}" if words else "")
