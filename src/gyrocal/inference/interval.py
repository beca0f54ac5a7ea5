"""The reference interval chosen from the data (``reference_interval_s: auto``): a pilot fit of the
channel model at every sample, whose residual's smoothness (`smoothness`) names the interval.

A reference whose error is smooth at its own rate (motion capture at 100 Hz) cannot be weighed by any
noise model here, but its samples every few knees can. Which interval that is depends on the
residual after the fit, not on the raw error: the nominal parameters' systematics make a 1 s
RepoIMU trial look smooth (the pilot then asked for 10 s), where a fit leaves it white. The pilot is
the baseline channel model (scale factors, misalignments, biases), the same for every model variant of
the run so that their comparison holds, weighed at the stated noise: a WLS from the classic estimate.

The fit is needed only where the nominal error itself is smooth: the parameters' errors add smooth
increments to it (a bias's are constant, which the measure removes), so a nominal error no smoother
than the noise model allows leaves a residual that is not smooth either, and every sample is used
with no fit (a few milliseconds on the default campaign, where the fit takes 1.7 s).
"""

from dataclasses import dataclass

import numpy as np

from gyrocal.errors import InputError
from gyrocal.inference import classic, identification, noise, smoothness
from gyrocal.inference.estimate import wls
from gyrocal.inference.preprocess import error_angles
from gyrocal.model import effects
from gyrocal.model.channels import ChannelParams
from gyrocal.model.spec import ModelSpec

__all__ = ["AUTO", "Choice", "choose", "nominal", "pilot", "requested"]

AUTO = "auto"
"""The config value of ``reference_interval_s`` that asks for the interval to be chosen from the data."""


@dataclass(frozen=True)
class Choice:
    """The reference interval the pilot fit named, with what it measured."""

    interval_s: float
    """Star-tracker samples kept about every this many seconds (0: every one)."""
    measured: list
    """Each maneuver's `smoothness.Smoothness`: of the nominal error, or where that is smooth, of the pilot's residual."""
    fitted: bool
    """Whether ``measured`` is of the pilot fit's residual (the nominal error was smooth)."""

    @property
    def reason(self) -> str:
        """The choice in words, for the log and the report."""
        what = "the baseline model's residual fitted at every sample" if self.fitted else "the nominal error"
        if not self.interval_s:
            return (f"every reference sample is used: {what} is not smooth at the sampling interval on any "
                    f"maneuver (its increments grow as lag^{_largest(self.measured)} at most)")
        smooth = [s for s in self.measured if s.smooth]
        worst = max(smooth, key=lambda s: s.exponent[0])
        return (f"the reference is used every {self.interval_s:.3g} s: {what} is smooth at the sampling interval "
                f"on {', '.join(s.maneuver for s in smooth)} (on {worst.maneuver} its increments grow as "
                f"lag^{worst.exponent[0]:.2f} from {worst.interval_s:.3g} s, where white noise, the gyro's walk and "
                f"a Gauss-Markov part grow at most as lag^0.5, and faster up to {max(s.knee_s for s in smooth):.3g} "
                f"s, the knee); {smoothness.KNEE_INTERVAL_FACTOR:g} knees, rounded up to 1, 2 or 5 times a power of "
                "ten, apart, samples of such an error are all but uncorrelated")

    def record(self) -> dict:
        """What the run writes of it (`gyrocal.pipeline`'s ``reference_interval.json``)."""
        return {"requested": AUTO, "interval_s": self.interval_s, "fitted": self.fitted, "reason": self.reason,
                "maneuvers": {s.maneuver: {"sampling_interval_s": round(s.interval_s, 6),
                                           "first_exponent": round(float(s.exponent[0]), 3) if len(s.exponent) else None,
                                           "smooth": s.smooth, "knee_s": round(s.knee_s, 6)} for s in self.measured}}


def _largest(measured) -> str:
    first = [float(s.exponent[0]) for s in measured if len(s.exponent)]
    return f"{max(first):.2f}" if first else "?"


def pilot(maneuvers, stated_noise: dict, sensor_class=None):
    """The baseline channel model fitted at the stated noise (WLS from the classic estimate), and each
    maneuver's linearisation about it."""
    fx = effects.resolve("baseline", effects.BASELINE, {})
    spec = ModelSpec.build("pilot", fx, maneuvers[0].channels).with_sensor_class(sensor_class)
    spec = spec.with_prior_only(identification.unflown(maneuvers, spec))
    est = wls(maneuvers, spec, stated_noise, noise.log_sigma_of(stated_noise), classic.classic_start(maneuvers, spec))
    return est, [est.linearize(maneuvers, m) for m in range(len(maneuvers))]


def nominal(data) -> smoothness.Smoothness:
    """The growth of a maneuver's nominal error (its first channel set's, in body axes: the tracker's
    frame but for the mounting)."""
    lags, exponent, se = smoothness.growth(error_angles(data, data.sets[0], ChannelParams.zeros(data.channels)))
    interval = float(np.median(np.diff(data.st_time))) if len(data.st_time) > 1 else 0.0
    return smoothness.Smoothness(data.id, interval, lags, exponent, se)


def choose(maneuvers, stated_noise: dict, sensor_class=None) -> Choice:
    """The reference interval at which the residual is no smoother than the noise model allows
    (`smoothness.recommended_interval_s`; 0 where it is not smooth at its own rate): of the nominal
    error where that is not smooth, else of the pilot fit's residual."""
    measured = [nominal(d) for d in maneuvers]
    if not any(s.smooth for s in measured):
        return Choice(0.0, measured, False)
    est, lins = pilot(maneuvers, stated_noise, sensor_class)
    measured = smoothness.of_estimate(maneuvers, est, lins)
    return Choice(float(smoothness.recommended_interval_s(measured)), measured, True)


def requested(value) -> float | None:
    """``reference_interval_s`` as a number of seconds, or None where it asks for `AUTO`."""
    if isinstance(value, str):
        if value.strip().lower() != AUTO:
            raise InputError(f"reference_interval_s must be a number of seconds or {AUTO!r}, got {value!r}")
        return None
    value = float(value)
    if not np.isfinite(value) or value < 0:
        raise InputError(f"reference_interval_s must be 0 or more seconds, got {value!r}")
    return value
