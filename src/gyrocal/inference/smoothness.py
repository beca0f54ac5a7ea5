"""How fast the residual's increments grow with the lag, against what the noise model can produce.

White noise, the gyro's random walk and a first-order Gauss-Markov part, and any sum of them, have
a concave variogram ``gamma(k) = Var(r_(j+k) - r_j)`` (constant, linear, ``2 s^2 (1 - phi^k)``)
that starts at or above zero: doubling the lag multiplies the rms increment by at most sqrt 2, a
growth exponent ``0.5 log2(gamma(2k) / gamma(k))`` of at most 1/2. A residual whose increments grow
faster, nearly in proportion to the lag, is smooth at the sampling interval (an error whose rate is
correlated: a motion-capture system's pose-dependent error, a filtered reference), which the noise
model cannot represent; the lag from which it grows no faster than the model allows (the knee) is
where that smooth error has decorrelated.
"""

from dataclasses import dataclass

import numpy as np

__all__ = ["KNEE_INTERVAL_FACTOR", "MIN_INCREMENTS", "SIGNIFICANCE_SE", "Smoothness", "describe", "growth", "of_maneuver",
           "recommended_interval_s"]

MODEL_EXPONENT_MAX = 0.5
"""The largest growth exponent a concave variogram allows (the random walk's)."""

SIGNIFICANCE_SE = 3.0
"""A growth exponent more than this many standard errors above `MODEL_EXPONENT_MAX` is beyond the model."""

MIN_INCREMENTS = 20
"""Lags with fewer independent increments than this (per axis) are not judged."""

KNEE_INTERVAL_FACTOR = 5.0
"""The reference interval recommended for a smooth error: this many knees, where consecutive samples of
the smooth error correlate by under 2 %, whatever its shape between the two usual ones. A
second-order Gauss-Markov error (correlation ``(1 + t/T) e^(-t/T)``) has its knee (growth exponent
1/2) at 1.26 T, and 5 knees apart its samples correlate by 0.014 (by 0.18 at 2.5 knees); white noise
through a Gaussian kernel of sd ``s``, knee 1.56 s, by 2e-7. RepoIMU at 100 Hz: knee 0.08 s; used
every 0.2 s the ARW comes out twice the 1 s run's and the intervals up to twice as wide, every 0.5 s
both agree with it and the intervals are narrower (`docs/real-data.md`, step 11)."""


@dataclass(frozen=True)
class Smoothness:
    """One maneuver's increment growth: per lag (doubling from one sample) its exponent to the next."""

    maneuver: str
    interval_s: float
    """The median star-tracker sampling interval."""
    lags: np.ndarray
    """Lags in samples, 1, 2, 4, ..."""
    exponent: np.ndarray
    """Growth exponent from each lag to twice it."""
    se: np.ndarray
    """Its approximate standard error."""

    @property
    def beyond(self) -> np.ndarray:
        """Where the growth is significantly faster than any white, walk and Gauss-Markov sum allows."""
        return self.exponent > MODEL_EXPONENT_MAX + SIGNIFICANCE_SE * self.se

    @property
    def smooth(self) -> bool:
        """True where the residual is smooth at the sampling interval (the first lag is `beyond`)."""
        return bool(len(self.lags)) and bool(self.beyond[0])

    @property
    def knee_s(self) -> float:
        """The lag (s) where the growth that starts `beyond` the model's at the first lag ends, the smooth
        error's decorrelation; 0 where the residual is not `smooth` (a growth beyond it at longer lags
        only is structure of another kind)."""
        run = int(np.argmin(np.append(self.beyond, False)))
        return float(self.lags[run - 1] * 2 * self.interval_s) if run else 0.0


def growth(residual: np.ndarray):
    """Lags (samples, doubling), growth exponents and their standard errors of a (M, 3) residual, the
    increments' variance summed over the axes (their mean removed: a constant rate adds nothing). The
    error treats each lag's increments as ``3 (M - k) / k`` independent ones, which overstates it for
    increments that overlap (it errs against calling a residual smooth)."""
    r = np.asarray(residual, dtype=float)
    m = len(r)
    lags = 2 ** np.arange(0, max(int(np.log2(max(m, 1))), 1))
    lags = lags[3 * (m - 2 * lags) / (2 * lags) >= MIN_INCREMENTS]
    var = np.array([np.sum(np.var(r[k:] - r[:-k], axis=0)) for k in np.concatenate([lags, 2 * lags[-1:]])])
    exponent = 0.5 * np.log2(var[1:] / var[:-1])
    n = 3.0 * (m - lags) / lags
    n2 = 3.0 * (m - 2 * lags) / (2 * lags)
    se = 0.5 / np.log(2.0) * np.sqrt(2.0 / n + 2.0 / n2)
    return lags, exponent, se


def of_maneuver(lin) -> Smoothness:
    """The growth of a linearised maneuver's residual (`errormodel.Linearization`, its first channel
    set) seen in the tracker's frame, where its white and Gauss-Markov parts are defined."""
    body = np.einsum("mji,mj->mi", lin.st_matrix, lin.z[:, 0])
    interval = float(np.median(lin.st_dt[1:])) if len(lin.st_dt) > 1 else 0.0
    lags, exponent, se = growth(body) if len(body) >= 8 else (np.zeros(0, int), np.zeros(0), np.zeros(0))
    return Smoothness(lin.maneuver, interval, lags, exponent, se)


def recommended_interval_s(measured) -> float:
    """The reference interval at which a smooth error looks white or Gauss-Markov: `KNEE_INTERVAL_FACTOR`
    times the longest knee of the smooth maneuvers, rounded up to 1, 2 or 5 times a power of ten."""
    knee = max((s.knee_s for s in measured if s.smooth), default=0.0)
    if knee <= 0:
        return 0.0
    raw = KNEE_INTERVAL_FACTOR * knee
    decade = 10.0 ** np.floor(np.log10(raw))
    return float(next(f * decade for f in (1, 2, 5, 10) if f * decade >= raw * (1 - 1e-9)))


def describe(measured) -> str:
    """The smooth maneuvers in words, with the reference interval to use; "" where none is smooth."""
    smooth = [s for s in measured if s.smooth]
    if not smooth:
        return ""
    worst = max(smooth, key=lambda s: s.exponent[0])
    dt = worst.interval_s
    interval = recommended_interval_s(measured)
    return (f"the residual is smooth at the sampling interval on {', '.join(s.maneuver for s in smooth)}: on "
            f"{worst.maneuver} its increments grow as lag^{worst.exponent[0]:.2f} from {dt:.3g} to {2 * dt:.3g} s "
            f"(white noise, the gyro's walk and a Gauss-Markov part grow at most as lag^0.5), and faster than that "
            f"up to {max(s.knee_s for s in smooth):.3g} s. The reference's error, or an effect the model lacks, "
            f"changes slower than its samples come, and no noise model here can follow it: use the reference every "
            f"{interval:.3g} s or more, where it does not (--config reference_interval_s={interval:.3g}, or "
            f"gyrocal import --reference-interval {interval:.3g})")
