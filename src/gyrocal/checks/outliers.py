"""The star-tracker outlier and excursion screen: samples far off their neighbours, or runs that
leave the error's trend and come back, beyond what the data's own noise allows. They are listed
with their line and kept out of the fit."""

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.special import chdtr, chdtri, gammaincinv

from gyrocal.checks.sensing import OUTLIER_REACH, Sensed, neighbour_residual
from gyrocal.inference.errormodel import cumulative_at_st
from gyrocal.model.units import rad_to_arcsec

__all__ = [
    "EXCURSION_EDGE_CUT", "EXCURSION_MAX_S", "EXCURSION_TREND_S", "OUTLIER_FALSE_ALARMS", "OUTLIER_MAX_RUN", "Outlier",
    "chi2_quantile", "excursion_runs", "isolated_runs", "mahalanobis2", "outlier_distances", "robust_covariance",
    "running_median", "runs",
    "screen", "trend_distances"
]

OUTLIER_FALSE_ALARMS = 0.01
"""Expected star-tracker samples wrongly called outliers per campaign, under the data's own noise."""

OUTLIER_MAX_RUN = 3
"""An outlier stands alone: a wrong star identification or a reference glitch lasts a sample or
a few. Longer runs beyond the noise are excursions (`EXCURSION_MAX_S`) or structure for the
model, which stays in the fit."""

EXCURSION_MAX_S = 5.0
"""A reference excursion leaves the trend of the error between the sensors with a jump and comes
back within this time: a motion-capture marker swap, or a star tracker's filter holding a wrong
attitude. The jump must be one the motion does not explain (`outlier_distances` takes out what
scale errors, misalignments, a time offset and a nonlinearity would leave), since a scale error
over a there-and-back turn also comes back; an unexplained error of the gyros integrates: it
can step, but it cannot come back."""

EXCURSION_TREND_S = 3 * EXCURSION_MAX_S
"""The error's trend is its running median over this window: an excursion shorter than half of it
does not move the median."""

EXCURSION_EDGE_CUT = float(2 * gammaincinv(1.5, 0.99))
"""An excursion extends on either side while its samples stay off the trend beyond this (the
chi-square 99 % point on three degrees of freedom), so that its edges leave the fit with it."""


@dataclass
class Outlier:
    maneuver: str
    time_s: float
    line: int
    """Line of ``star_tracker.csv`` (the header is line 1)."""
    size_arcsec: float
    """Departure from its neighbours that the motion does not explain (`outlier_distances`), or,
    in an excursion, from the error's trend (`trend_distances`)."""
    mahalanobis: float
    """The same departure in standard deviations of the data's own noise."""
    kind: str = "outlier"
    """``outlier`` (a sample or a few) or ``excursion`` (a run that leaves the trend and comes back)."""



def chi2_quantile(q, df):
    """The chi-square quantile as `scipy.stats.chi2.ppf` computes it, from `scipy.special`: validate
    and each preprocess job are processes of their own, and scipy.stats costs 0.3 s to import."""
    return 2 * gammaincinv(df / 2, q)



def outlier_distances(sensed: Sensed):
    """Each star-tracker sample's departure from its neighbours (`neighbour_residual` of the error
    of eq. 4, rad, body axes), less what the motion explains, and its squared Mahalanobis
    distance under the robust covariance of those departures: the data's own noise.

    The error between the sensors bends only where the motion does. An error linear in the
    rotation (scale, misalignment), in the rate (a latency or time offset) or in the rate's
    signed square (a nonlinearity) leaves, where the motion bends, a departure proportional to
    the same departure of the cumulative angle, the rate or the square-rate integral; these
    nine regressors are fitted on the inliers and taken out, so only what the motion cannot
    explain remains.
    """
    data, body, err = sensed.data, sensed.body, sensed.departures
    rate = body / data.dt[:, None]
    k, frac = data.st_interval()
    motion = neighbour_residual(np.concatenate([cumulative_at_st(body, k, frac), rate[k],
                                                cumulative_at_st(body * np.abs(rate), k, frac)], axis=1))
    inside = np.ones(len(err), dtype=bool)
    inside[[0, -1]] = False
    cut = chi2_quantile(0.999, 3)
    for _ in range(3):
        coef, *_ = np.linalg.lstsq(motion[inside], err[inside], rcond=None)
        resid = err - motion @ coef
        cov = robust_covariance(resid[inside])
        d2 = mahalanobis2(resid, cov)
        inside = (d2 < cut) & inside
    return resid, d2


def trend_distances(sensed: Sensed):
    """Each star-tracker sample's error between the sensors (eq. 4, nominal parameters, rad, body
    axes) less its trend, the running median over `EXCURSION_TREND_S`, and its squared Mahalanobis
    distance under the robust covariance of those deviations. Scale errors, misalignments and
    biases bend the error slowly and the median follows them; a reference excursion leaves it."""
    err = sensed.error
    window = int(min(len(err), max(3, round(EXCURSION_TREND_S / float(np.median(sensed.dt))))))
    dev = err - running_median(err, window | 1)
    return dev, mahalanobis2(dev, robust_covariance(dev))


def running_median(x: np.ndarray, window: int) -> np.ndarray:
    """The centred running median of each column over an odd ``window``, the ends padded with the
    first and last rows (`scipy.ndimage.median_filter`'s ``nearest``, to the bit): pandas' rolling
    median keeps a sorted window, O(N log W) where the filter's selection is O(N W) (42 of validate's
    47 s on a 200-s trial at 286 Hz with the 15-s window)."""
    half = window // 2
    padded = np.concatenate([np.repeat(x[:1], half, axis=0), x, np.repeat(x[-1:], half, axis=0)])
    return pd.DataFrame(padded).rolling(window, center=True).median().to_numpy()[half:half + len(x)]


def excursion_runs(near, beyond, jumps, st_time, max_s: float) -> np.ndarray:
    """Excursions: runs of ``near`` (off the trend beyond a lower cut) that hold a jump (a sample off
    its neighbours, ``jumps``: a wander of the error leaves its trend too, but smoothly) and whose
    core, the samples ``beyond`` the outlier threshold, lasts at most ``max_s`` and lies inside the
    maneuver, so that the error is seen to come back. The run's edges, off the trend but not
    beyond the threshold, go with it, unless they stretch it past twice ``max_s``."""
    n = len(near)
    out = np.zeros(n, dtype=bool)
    for a, b in runs(near):
        core = np.flatnonzero(beyond[a:b]) + a
        if core.size == 0 or not jumps[a:b].any():
            continue
        c0, c1 = core[0], core[-1] + 1
        if c0 == 0 or c1 == n or st_time[c1] - st_time[c0 - 1] > max_s:
            continue
        if st_time[min(b, n - 1)] - st_time[max(a - 1, 0)] <= 2 * max_s:
            out[a:b] = True
        else:
            out[c0:c1] = True
    return out


def mahalanobis2(x, cov) -> np.ndarray:
    """(N,) squared Mahalanobis distance of each row of ``x`` (N, p) under ``cov``."""
    return np.einsum("mi,ij,mj->m", x, np.linalg.pinv(cov), x)


def robust_covariance(x, iterations=5, quantile=0.99) -> np.ndarray:
    """Covariance of the bulk of ``x`` (N, p): refit on the points inside the ``quantile`` ellipsoid,
    corrected for the truncation (a normal's tails are cut, not outliers')."""
    p = x.shape[1]
    scale = 1.4826 * np.median(np.abs(x - np.median(x, axis=0)), axis=0) + 1e-15
    cov = np.diag(scale**2)
    cut = chi2_quantile(quantile, p)
    factor = chdtr(p + 2, cut) / chdtr(p, cut)
    for _ in range(iterations):
        d2 = mahalanobis2(x, cov)
        inside = x[d2 < cut]
        cov = inside.T @ inside / len(inside) / factor
    return cov



def runs(mask):
    """``(start, end)`` of each run of consecutive True in ``mask``, ``end`` past its last entry."""
    edges = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    return zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1))


def isolated_runs(mask, max_run: int) -> np.ndarray:
    """The entries of ``mask`` that sit in runs of at most ``max_run`` consecutive True."""
    out = np.zeros(len(mask), dtype=bool)
    for a, b in runs(mask):
        if b - a <= max_run:
            out[a:b] = True
    return out




def screen(campaign, screened, findings):
    """List the outliers and excursions of every maneuver with their ``star_tracker.csv`` line, at a
    threshold that keeps the expected false alarms per campaign at `OUTLIER_FALSE_ALARMS`; runs too
    long for either are structure for the model, and a warning. ``screened`` holds each maneuver's
    data with its `outlier_distances` and `trend_distances`."""
    n_total = sum(len(d2) for _, _, d2, _, _ in screened)
    threshold = chdtri(3, OUTLIER_FALSE_ALARMS / max(n_total, 1))
    for data, resid, d2, dev, d2_trend in screened:
        lines = campaign.lines["star_tracker.csv"][np.searchsorted(campaign.st_time, data.st_time)]
        beyond = d2 > threshold
        isolated = isolated_runs(beyond, OUTLIER_MAX_RUN)
        away = excursion_runs(d2_trend > EXCURSION_EDGE_CUT, d2_trend > threshold, beyond, data.st_time,
                              EXCURSION_MAX_S) & ~isolated
        for j in np.flatnonzero(isolated):
            findings.outliers.append(Outlier(data.id, float(data.st_time[j]), int(lines[j]),
                                             float(rad_to_arcsec(np.linalg.norm(resid[j]))),
                                             float(np.sqrt(d2[j]))))
        for j in np.flatnonzero(away):
            findings.outliers.append(Outlier(data.id, float(data.st_time[j]), int(lines[j]),
                                             float(rad_to_arcsec(np.linalg.norm(dev[j]))),
                                             float(np.sqrt(d2_trend[j])), "excursion"))
        beside = np.convolve(away, np.ones(2 * OUTLIER_REACH + 1), mode="same") > 0
        structure = int((beyond & ~isolated & ~beside).sum())
        if structure:
            findings.warn("outliers",
                f"maneuver {data.id}: {structure} star-tracker samples in runs of more than {OUTLIER_MAX_RUN} depart "
                "from their neighbours beyond the noise: structure the model should explain, not outliers; "
                "they stay in the fit")
