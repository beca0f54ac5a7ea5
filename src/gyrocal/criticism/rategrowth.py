"""How strongly a white-noise model's innovations call for a reference error that grows with the rate
(`st_jitter`): the likelihood ratio of innovations whose variance grows with ``|omega|^2`` against
innovations of one variance.

A timing jitter ``sigma_t`` between the reference's clock and the gyros' leaves each reference sample
off by ``omega dt``: after the first differences the white model takes, sample j's error variance
grows by about ``sigma_t^2 (|omega_j|^2 + |omega_(j-1)|^2) / 3`` per axis. The model of the
standardised innovations is ``w ~ N(0, s^2 (1 + g q_j))`` with ``q_j`` that mean of the two squared
rates, ``g >= 0``; ``s^2`` is profiled, ``g`` searched on a grid, and the likelihood ratio against
``g = 0`` scored as a chi-square on one degree of freedom, halved (``g`` sits on its boundary under
the null). Like `correlation`'s, the ratio of a large systematic error grows as the log of its
energy, not as the energy: the ranking's deterministic candidates stay in the same currency. It
uses the first channel set's three innovations per sample, where the reference's error is.
"""

import numpy as np
from scipy.special import log_ndtr

__all__ = ["GROWTH_GRID", "RATE_DF", "growth_gain", "per_sample", "score"]

GROWTH_GRID = np.geomspace(1e-3, 1e4, 43)
"""Growths searched, ``g`` times the mean of ``q`` (the variance's growth at the campaign's mean squared rate)."""

RATE_DF = 1
"""Degrees of freedom of the likelihood ratio: the growth ``g``."""


def per_sample(w: np.ndarray, stride: int, rate_rad_s: np.ndarray, values: int = 3) -> tuple:
    """A maneuver's first ``values`` innovations per sample of ``w`` (``stride`` values a sample), flat,
    and each one's ``q`` (rad^2/s^2): the mean squared body rate at its sample and the one before."""
    w = np.asarray(w, dtype=float).reshape(-1, stride)[:, :values]
    squared = np.sum(np.asarray(rate_rad_s, dtype=float) ** 2, axis=1)
    q = 0.5 * (squared + np.concatenate([squared[:1], squared[:-1]]))
    return w.ravel(), np.repeat(q, w.shape[1])


def growth_gain(w: np.ndarray, q: np.ndarray) -> tuple:
    """Twice the profiled Gaussian log-likelihood ratio of ``var w = s^2 (1 + g q)`` over ``s^2`` at the
    best ``g`` of `GROWTH_GRID` (0 where none beats the constant), and that ``g`` (per rad^2/s^2)."""
    w2, q = np.asarray(w, dtype=float) ** 2, np.asarray(q, dtype=float)
    n, mean_q = len(w2), float(np.mean(q))
    if n == 0 or mean_q <= 0:
        return 0.0, 0.0
    constant = n * np.log(np.mean(w2))
    growth = GROWTH_GRID[:, None] / mean_q
    scale = 1.0 + growth * q[None, :]
    fitted = n * np.log(np.mean(w2[None, :] / scale, axis=1)) + np.sum(np.log(scale), axis=1)
    best = int(np.argmin(fitted))
    gain = float(constant - fitted[best])
    return (gain, float(growth[best, 0])) if gain > 0 else (0.0, 0.0)


def score(parts) -> dict:
    """The likelihood ratio over the maneuvers' pooled ``(w, q)`` (`per_sample`), its growth ``g`` per
    rad^2/s^2, and ``log10_p`` (chi-square on `RATE_DF`, halved for the boundary; the ranking's entry scores
    the same ratio unhalved, as its other candidates)."""
    w = np.concatenate([p[0] for p in parts])
    q = np.concatenate([p[1] for p in parts])
    gain, growth = growth_gain(w, q)
    # half of P(chi2_1 > x) = 2 Phi(-sqrt x): Phi(-sqrt x), finite however large x
    log10_p = float(log_ndtr(-np.sqrt(gain)) / np.log(10)) if gain > 0 else 0.0
    return {"chi2": round(gain, 2), "growth_per_rad2_s2": float(f"{growth:.4g}"), "log10_p": round(log10_p, 2)}
