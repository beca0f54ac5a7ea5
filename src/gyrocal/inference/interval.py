"""The reference interval chosen from the data (``reference_interval_s: auto``): a pilot fit of the
channel model at every sample, whose residual's smoothness (`smoothness`) names the interval.

A reference whose error is smooth at its own rate (motion capture at 100 Hz) cannot be weighed by any
noise model here, but its samples every few knees can. Which interval that is depends on the
residual after the fit, not on the raw error: the nominal parameters' systematics make a 1 s
RepoIMU trial look smooth (the pilot then asked for 10 s), where a fit leaves it white. The pilot is
the baseline channel model (scale factors, misalignments, biases), the same for every model variant of
the run so that their comparison holds, with its noise scales estimated as every model's are.

The fit is needed only where the nominal error itself is smooth: the parameters' errors add smooth
increments to it (a bias's are constant, which the measure removes), so a nominal error no smoother
than the noise model allows leaves a residual that is not smooth either, and every sample is used
with no fit (a tenth of a second on the default campaign, where the fit would take 2.7 s). The increments are
taken within runs of samples without a gap: the nominal parameters' error over an unseen slew steps
across a gap and would hide a smooth error (found by an independent review).
"""

from dataclasses import dataclass

import numpy as np

from gyrocal.errors import InputError
from gyrocal.inference.fit.pilot import pilot
from gyrocal.inference.noise import smoothness
from gyrocal.io.telemetry import TelemetryError
from gyrocal.maneuvers.preprocess import error_angles, slice_maneuver
from gyrocal.model.channels import ChannelParams

__all__ = ["AUTO", "Choice", "choose", "nominal", "requested", "shorter", "slice_all", "sliced"]

AUTO = "auto"
"""The config value of ``reference_interval_s`` that asks for the interval to be chosen from the data."""


@dataclass(frozen=True)
class Choice:
    """The reference interval the data named, with what was measured."""

    interval_s: float
    """Star-tracker samples kept about every this many seconds (0: every one)."""
    measured: list
    """Each maneuver's `smoothness.Smoothness`: of the nominal error, or where that is smooth, of the pilot's residual."""
    fitted: bool
    """Whether ``measured`` is of the pilot fit's residual (the nominal error was smooth)."""

    @property
    def reason(self) -> str:
        """The choice in words, for the log and the report."""
        what = ("the baseline model's residual, fitted at every sample with its noise scales estimated,"
                if self.fitted else "the nominal error")
        if not self.interval_s:
            s = max(self.measured, key=lambda s: s.exponent[0] if len(s.exponent) else -np.inf)
            growth = (f" (its increments grow at most as lag^{s.exponent[0]:.2f}, on {s.maneuver}, where the limit "
                      f"is {s.limit[0]:.2f})" if len(s.exponent) else "")
            return f"every reference sample is used: {what} is not smooth at the sampling interval{growth}"
        smooth = [s for s in self.measured if s.smooth]
        worst = max(smooth, key=lambda s: s.knee_s)
        return (f"the reference is used every {self.interval_s:.3g} s: {what} is smooth at the sampling interval "
                f"on {', '.join(s.maneuver for s in smooth)}. On {worst.maneuver} its increments grow as "
                f"lag^{worst.exponent[0]:.2f} from {worst.interval_s:.3g} s (limit {worst.limit[0]:.2f}: white noise, "
                f"the gyro's walk and a Gauss-Markov part grow at most as lag^0.5) and faster up to "
                f"{worst.knee_s:.3g} s, the knee; {smoothness.KNEE_INTERVAL_FACTOR:g} knees, "
                f"{smoothness.KNEE_INTERVAL_FACTOR * worst.knee_s:.3g} s, rounded up to 1, 2 or 5 times a power of "
                "ten, is where samples of such an error are all but uncorrelated")

    def record(self, used_s=None) -> dict:
        """What the run writes of it (``preprocess/reference_interval.json``); ``used_s``: per maneuver the
        interval it was used at, where a short one could not take `interval_s` (`slice_all`)."""
        used_s = used_s or {}
        short = [f"{m} every {every:g} s" for m, every in used_s.items() if every != self.interval_s]
        reason = self.reason + (f"; too short to keep 10 samples at that interval, {', '.join(short)}" if short else "")
        return {"requested": AUTO, "interval_s": self.interval_s, "fitted": self.fitted, "reason": reason,
                "maneuvers": {s.maneuver: {"sampling_interval_s": round(s.interval_s, 6),
                                           "first_exponent": round(float(s.exponent[0]), 3) if len(s.exponent) else None,
                                           "limit": round(float(s.limit[0]), 3) if len(s.exponent) else None,
                                           "smooth": s.smooth, "knee_s": round(s.knee_s, 6),
                                           "interval_s": used_s.get(s.maneuver, self.interval_s)}
                              for s in self.measured}}


def nominal(data) -> smoothness.Smoothness:
    """The growth of a maneuver's nominal error (its first channel set's, in body axes: the tracker's
    frame but for the mounting), of its increments within runs of samples without a gap
    (`smoothness.contiguous_runs`)."""
    error = error_angles(data, data.sets[0], ChannelParams.zeros(data.channels))
    lags, exponent, se = smoothness.growth(error, smoothness.contiguous_runs(data.st_time))
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


def shorter(interval_s: float) -> float:
    """The next interval below ``interval_s`` on the 1, 2, 5 ladder (5 -> 2 -> 1 -> 0.5 ...)."""
    decade = 10.0 ** np.floor(np.log10(interval_s) + 1e-9)
    mantissa = round(interval_s / decade)
    return float({5: 2, 2: 1}.get(mantissa, 0.5) * decade)


def slice_all(campaign, outlier_times_s, interval_s: float, usable_from_s: float) -> tuple:
    """Every maneuver sliced at ``interval_s``, or, one too short to keep 10 samples at it, at the longest
    interval on the 1, 2, 5 ladder below it that does (every sample below ``usable_from_s``, the
    sampling interval); and per maneuver the interval used. Every maneuver slices at every sample
    (the caller did), so an interval's only fault can be too few samples left."""
    sliced, used = [], {}
    for m in campaign.maneuvers:
        every = interval_s
        while True:
            try:
                sliced.append(slice_maneuver(campaign, m.id, outlier_times_s, every))
                break
            except TelemetryError:
                every = shorter(every)
                every = every if every >= usable_from_s else 0.0
        used[m.id] = every
    return sliced, used


def sliced(campaign, outlier_times_s, seconds: float | None, stated_noise: dict | None, sensor_class=None) -> tuple:
    """Every maneuver sliced as ``reference_interval_s`` asks (``seconds``, `requested`'s: None for `AUTO`,
    which chooses with ``stated_noise``), and the record of the interval used and why
    (``preprocess/reference_interval.json``)."""
    every = [slice_maneuver(campaign, m.id, outlier_times_s, seconds or 0.0) for m in campaign.maneuvers]
    if seconds is not None:
        return every, {"requested": seconds, "interval_s": seconds, "fitted": False,
                       "reason": (f"the reference is used every {seconds:g} s, as the config sets (reference_interval_s)"
                                  if seconds else "every reference sample is used, as the config sets "
                                                  "(reference_interval_s = 0)")}
    choice = choose(every, stated_noise, sensor_class)
    if not choice.interval_s:
        return every, choice.record()
    thinned, used = slice_all(campaign, outlier_times_s, choice.interval_s, min(s.interval_s for s in choice.measured))
    return thinned, choice.record(used)


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
