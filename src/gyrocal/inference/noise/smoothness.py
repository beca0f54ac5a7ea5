"""How fast the residual's increments grow with the lag, against what the noise model can produce.

White noise, the gyro's random walk and a first-order Gauss-Markov part, and any sum of them, have
a concave variogram ``gamma(k) = Var(r_(j+k) - r_j)`` (constant, linear, ``2 s^2 (1 - phi^k)``)
that starts at or above zero: doubling the lag multiplies the rms increment by at most sqrt 2, a
growth exponent ``0.5 log2(gamma(2k) / gamma(k))`` of at most 1/2. A residual whose increments grow
faster, nearly in proportion to the lag, is smooth at the sampling interval (an error whose rate is
correlated: a motion-capture system's pose-dependent error, a filtered reference), which the noise
model cannot represent; the lag from which it grows no faster than the model allows (the knee) is
where that smooth error has decorrelated.

Two things of the model's own grow faster, and are kept out. A part fixed in one frame, seen from
another that turns, changes by the turn (``|omega k dt|^2`` in the variance, convex): the walk and
the initial attitude error are fixed in the inertial frame, the white and Gauss-Markov parts in the
tracker's; so a residual is called smooth only where it is smooth in both frames (a fast slew with
a large walk made the tracker frame's alone smooth on simulated campaigns whose model was right).
And the gyro's walk seen between gyro samples is interpolated, so its variance over a lag falls short
of the lag by up to a third of a gyro interval (`errormodel.walk_steps`): a negative constant that
makes it convex; the model's own shortfall, at the fitted ARW, is added back before the growth is
judged (a reference at 20 Hz, 0.05 arcsec, on gyros at 10 Hz was called smooth without it).
"""

from dataclasses import dataclass

import numpy as np

from gyrocal.maneuvers.preprocess import noise_groups

__all__ = ["GAP_STEP_FACTOR", "KNEE_INTERVAL_FACTOR", "MIN_INCREMENTS", "SIGNIFICANCE_SE", "Smoothness",
           "contiguous_runs", "describe",
           "fitted_walk_variances", "growth", "of_estimate", "of_maneuver", "recommended_interval_s", "walk_shortfall"]

MODEL_EXPONENT_MAX = 0.5
"""The largest growth exponent a concave variogram allows (the random walk's)."""

SIGNIFICANCE_SE = 3.0
"""A growth exponent more than this many standard errors above `MODEL_EXPONENT_MAX` is beyond the model."""

MIN_INCREMENTS = 20
"""Lags with fewer independent increments than this (per axis) are not judged."""

KNEE_INTERVAL_FACTOR = 5.0
"""The reference interval recommended for a smooth error: this many knees (`Smoothness.knee_s`), where
consecutive samples of the smooth error correlate by under 2 %, whatever its shape between the two
usual ones. A second-order Gauss-Markov error (correlation ``(1 + t/T) e^(-t/T)``) has its exponent
cross 1/2 at 1.26 T; its knee is 1 to 2 times that, and 5 knees apart its samples correlate by at
most 0.014 (by 0.18 at 2.5 crossings); white noise through a Gaussian kernel (crossing at 1.56 kernel
sd) by at most 2e-7. RepoIMU at 100 Hz: knee 0.08 s; used every 0.2 s the ARW comes out twice the
1 s run's and the intervals up to twice as wide, every 0.5 s both agree with it and the intervals
are narrower (`docs/real-data.md`, step 11)."""


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
    def limit(self) -> np.ndarray:
        """Per lag, the growth exponent beyond which the residual is smoother than the noise model allows:
        `MODEL_EXPONENT_MAX` plus `SIGNIFICANCE_SE` standard errors."""
        return MODEL_EXPONENT_MAX + SIGNIFICANCE_SE * self.se

    @property
    def beyond(self) -> np.ndarray:
        """Where the growth is significantly faster than any white, walk and Gauss-Markov sum allows."""
        return self.exponent > self.limit

    @property
    def smooth(self) -> bool:
        """True where the residual is smooth at the sampling interval (the first lag is `beyond`)."""
        return bool(len(self.lags)) and bool(self.beyond[0])

    @property
    def knee_s(self) -> float:
        """The lag (s) where the growth that starts `beyond` the model's at the first lag ends, the smooth
        error's decorrelation: the first doubled lag whose growth to twice it is not beyond, which is at
        or past the lag where the exponent crosses 1/2, and within twice it; 0 where the residual is not
        `smooth` (a growth beyond it at longer lags only is structure of another kind)."""
        run = int(np.argmin(np.append(self.beyond, False)))
        return float(self.lags[run - 1] * 2 * self.interval_s) if run else 0.0


def _lags(m: int) -> np.ndarray:
    """Lags (samples, doubling from one) with at least `MIN_INCREMENTS` independent increments to twice them."""
    lags = 2 ** np.arange(0, max(int(np.log2(max(m, 1))), 1))
    return lags[3 * (m - 2 * lags) / (2 * lags) >= MIN_INCREMENTS]


def _variogram(residual: np.ndarray, lags, runs=None) -> np.ndarray:
    """The increments' variance over each lag, summed over the axes (their mean removed: a constant
    rate adds nothing); with ``runs`` (a label per sample), only of increments within one run."""
    if runs is None:
        return np.array([np.sum(np.var(residual[k:] - residual[:-k], axis=0)) for k in lags])
    return np.array([np.sum(np.var((residual[k:] - residual[:-k])[runs[k:] == runs[:-k]], axis=0)) for k in lags])


def _exponents(variogram: np.ndarray) -> np.ndarray:
    return 0.5 * np.log2(variogram[1:] / variogram[:-1])


def _standard_errors(m: int, lags, pairs=None) -> np.ndarray:
    """The growth exponent's error, each lag's increments taken as ``3 (M - k) / k`` independent ones
    (``pairs``: the ``M - k`` increments at each lag and twice it, where fewer are counted): 2 to 3
    times the true one for increments that overlap (it errs against calling a residual smooth)."""
    at_k, at_2k = (m - lags, m - 2 * lags) if pairs is None else pairs
    n = 3.0 * at_k / lags
    n2 = 3.0 * at_2k / (2 * lags)
    return 0.5 / np.log(2.0) * np.sqrt(2.0 / n + 2.0 / n2)


def growth(residual: np.ndarray, runs=None):
    """Lags (samples, doubling), growth exponents and their standard errors of a (M, 3) residual; with
    ``runs`` (`contiguous_runs`), of its increments within each run alone, at the lags with enough of them."""
    r = np.asarray(residual, dtype=float)
    lags = _lags(len(r))
    if runs is None:
        return lags, _exponents(_variogram(r, np.append(lags, 2 * lags[-1:]))), _standard_errors(len(r), lags)
    counted = np.array([np.count_nonzero(runs[k:] == runs[:-k]) for k in np.append(lags, 2 * lags[-1:])])
    enough = 3 * counted[1:] / (2 * lags) >= MIN_INCREMENTS
    lags = lags[:np.argmin(np.append(enough, False))]
    if not len(lags):
        return lags, np.zeros(0), np.zeros(0)
    every = np.append(lags, 2 * lags[-1:])
    return (lags, _exponents(_variogram(r, every, runs)),
            _standard_errors(len(r), lags, (counted[:len(lags)], counted[1:len(lags) + 1])))


GAP_STEP_FACTOR = 1.5
"""A step longer than this many median sampling intervals ends a run of samples (`contiguous_runs`)."""


def contiguous_runs(time_s: np.ndarray) -> np.ndarray:
    """A label per sample, new after every step longer than `GAP_STEP_FACTOR` median steps: an error
    that grows during a gap (the nominal parameters' over an unseen slew) steps across it, and its
    increments over a lag counted in samples would then grow with the lag as a walk's do."""
    step = np.diff(np.asarray(time_s, dtype=float))
    if not len(step):
        return np.zeros(len(time_s), dtype=int)
    return np.concatenate([[0], np.cumsum(step > GAP_STEP_FACTOR * np.median(step))])


def walk_shortfall(st_dt_s, walk_var, walk_lag1, lags) -> np.ndarray:
    """Per unit ARW^2 and axis, how far the interpolated walk's variance over each lag falls short of the
    lag (s), averaged over the maneuver's samples: each step's shortfall ``st_dt - walk_var`` less twice
    the covariance with the step before (`errormodel.walk_steps`); zeros on the gyro grid."""
    st_dt_s = np.asarray(st_dt_s, dtype=float)
    step = st_dt_s - (st_dt_s if walk_var is None else np.asarray(walk_var, dtype=float))
    shared = np.zeros_like(step) if walk_lag1 is None else np.asarray(walk_lag1, dtype=float)
    c_step, c_shared = np.concatenate([[0.0], np.cumsum(step)]), np.concatenate([[0.0], np.cumsum(shared)])
    m = len(step)
    out = []
    for k in lags:
        j = np.arange(m - k)
        out.append(np.mean(c_step[j + k + 1] - c_step[j + 1] - 2.0 * (c_shared[j + k + 1] - c_shared[j + 2])))
    return np.array(out)


def fitted_walk_variances(maneuvers, estimate) -> list:
    """Each maneuver's fitted ARW^2 (rad^2/s): the `estimate.PointEstimate`'s, at its noise group's level."""
    index = noise_groups(maneuvers)[1]
    return [float(estimate.maneuver_variances(m, index[m])["walk"]) for m in range(len(maneuvers))]


def of_estimate(maneuvers, estimate, lins) -> list:
    """`of_maneuver` of each maneuver's linearisation ``lins`` about ``estimate``, at its fitted walk."""
    return [of_maneuver(lin, walk) for lin, walk in zip(lins, fitted_walk_variances(maneuvers, estimate))]


def of_maneuver(lin, walk_variance: float = 0.0) -> Smoothness:
    """The growth of a linearised maneuver's residual (`errormodel.Linearization`, its first channel
    set), the slower of its growths in the inertial frame and the tracker's, with the interpolated
    walk's shortfall at the fitted ``walk_variance`` (ARW^2, rad^2/s) added back."""
    interval = float(np.median(lin.st_dt[1:])) if len(lin.st_dt) > 1 else 0.0
    inertial = np.asarray(lin.z[:, 0], dtype=float)
    m = len(inertial)
    lags = _lags(m) if m >= 8 else np.zeros(0, int)
    if not len(lags):
        return Smoothness(lin.maneuver, interval, lags, np.zeros(0), np.zeros(0))
    every = np.append(lags, 2 * lags[-1:])
    added = 3.0 * walk_variance * walk_shortfall(lin.st_dt, lin.walk_var, lin.walk_lag1, every)
    tracker = np.einsum("mji,mj->mi", lin.st_matrix, inertial)
    exponent = np.minimum(_exponents(_variogram(inertial, every) + added), _exponents(_variogram(tracker, every) + added))
    return Smoothness(lin.maneuver, interval, lags, exponent, _standard_errors(m, lags))


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
            f"{interval:.3g} s or more, where it does not (--config reference_interval_s={interval:.3g}; when "
            f"importing, gyrocal import --reference-interval {interval:.3g})")
