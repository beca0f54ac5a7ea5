"""How strongly a white-noise model's innovations call for correlated reference noise
(`st_correlated_noise`): the lag-1 score test, and a scan of first-order Gauss-Markov shapes.

The lag-1 autocorrelation (``z = rho_1 sqrt(n)``) sees a short correlation time; a long one (30 s
at 1 Hz) spreads over many lags, where the white model's fitted walk absorbs much of it at lag 1,
and slow signatures (bias drift, a rate-dependent error) then out-scored it. Against innovations
``w`` correlated as ``I + s^2 R(phi)``, ``R_ij = phi^|i-j|``, the locally most powerful test at
``s = 0`` is the phi-weighted sum of the autocorrelations, ``z(phi) = sqrt(n) sum_k phi^k rho_k /
sqrt(sum_k phi^2k)``, about N(0, 1) under the white model (the ``rho_k`` about independent, each of
variance 1/n; fitting the model's parameters pulls it a little negative: conservative). It is
one-sided: a Gauss-Markov part correlates positively where the tracker's noise dominates the walk
per sample. The scan takes the first channel set's innovations, counted per value: the whitening
leaves the star tracker's error there, the other sets' innovations being the gyros' differences
(an independent review measured their summed autocorrelations at 0.0 against 2.6-3.1). The two are
combined by a weighted Bonferroni bound: `LAG1_WEIGHT` of the level to the lag-1 test (the
whiteness check's, a sample's 3 S values counted as one), the rest split over the scan's times.

A deterministic effect left out correlates the residual too, and its correlation can out-score its
own score test as it grows (the scan's z^2 grows as the effect's energy squared, the score test's
drop as the energy): `noiseranking` sets the noise below an effect that leaves it unexplained.
"""

import numpy as np
from scipy.special import chdtri, log_ndtr

__all__ = ["LAG1_WEIGHT", "MAX_LAG", "SCAN_TAU_SAMPLES", "autocovariances", "chi2_equivalent", "log_p", "scan",
           "score"]

SCAN_TAU_SAMPLES = (1.0, 3.0, 10.0, 30.0, 100.0)
"""Correlation times the scan tries, in sampling intervals."""

LAG1_WEIGHT = 0.8
"""The share of the test's level given to the lag-1 statistic (the rest shared by the scan)."""

MAX_LAG = 500
"""Lags (samples) the scan sums over: 5 times its longest correlation time."""


def autocovariances(w: np.ndarray, stride: int, max_lag: int = MAX_LAG, values: int | None = None) -> np.ndarray:
    """``sum_j w_j . w_(j+k)`` for k = 0 .. max_lag, of innovations ``w`` that come ``stride`` values per
    sample (axes within channel sets), summed over a sample's first ``values`` (all: None); by FFT."""
    series = np.asarray(w, dtype=float).reshape(-1, stride)[:, :values]
    m = len(series)
    size = 1 << int(np.ceil(np.log2(max(2 * m, 2))))
    spectrum = np.fft.rfft(series, n=size, axis=0)
    out = np.fft.irfft(np.sum(spectrum * spectrum.conj(), axis=1).real, n=size)[:min(max_lag, m - 1) + 1]
    return np.pad(out, (0, max_lag + 1 - len(out)))


def scan(acov: np.ndarray, n: int, tau_samples=SCAN_TAU_SAMPLES) -> np.ndarray:
    """``z(phi)`` at each correlation time (``phi = exp(-1/tau)``), from pooled autocovariances ``acov``
    (lag 0 first) of ``n`` samples."""
    rho = acov[1:] / acov[0]
    k = np.arange(1, len(rho) + 1)
    weights = np.exp(-k[None, :] / np.asarray(tau_samples, dtype=float)[:, None])
    return np.sqrt(n) * (weights @ rho) / np.sqrt(np.sum(weights**2, axis=1))


def log_p(z_lag1: float, z_scan) -> float:
    """The natural log of the combined p-value: the lag-1 test two-sided (``z^2`` on one degree of
    freedom) at `LAG1_WEIGHT`, the scan's largest one-sided, each of its members at an equal share of
    the rest; at most 0."""
    lag1 = np.log(2.0) + log_ndtr(-abs(z_lag1)) - np.log(LAG1_WEIGHT)
    share = (1.0 - LAG1_WEIGHT) / max(len(z_scan), 1)
    best = log_ndtr(-float(np.max(z_scan))) - np.log(share) if len(z_scan) else 0.0
    return float(min(0.0, lag1, best))


def chi2_equivalent(log_p_value: float) -> float:
    """The chi-square on one degree of freedom with this log p-value (for the ranking's ``chi2_drop``):
    scipy's inverse where the p-value is a double, else the tail's asymptotic inverse
    (``log p = log 2 + log Phi(-z)``, ``Phi(-z) ~ phi(z) / z (1 - 1/z^2 + 3/z^4)``), iterated."""
    if log_p_value > -700:
        return float(chdtri(1, np.exp(log_p_value)))
    z = np.sqrt(-2.0 * log_p_value)
    for _ in range(20):
        tail = np.log(z) - np.log1p(-1.0 / z**2 + 3.0 / z**4)
        z = np.sqrt(2.0 * (np.log(2.0) - log_p_value - 0.5 * np.log(2 * np.pi) - tail))
    return float(z * z)


def score(acov_first: np.ndarray, n_values: int, z_lag1: float) -> dict:
    """The scan over the first channel set's pooled autocovariances ``acov_first`` of ``n_values``
    innovations, its best correlation time and the combined ``log10_p`` with the lag-1 ``z_lag1``."""
    z_scan = scan(acov_first, n_values)
    best = int(np.argmax(z_scan))
    return {"z": round(float(z_scan[best]), 2), "tau_samples": SCAN_TAU_SAMPLES[best],
            "log10_p": round(log_p(z_lag1, z_scan) / np.log(10), 2)}
