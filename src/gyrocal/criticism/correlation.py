"""How strongly a white-noise model's innovations call for correlated reference noise
(`st_correlated_noise`): the likelihood ratio of white plus first-order Gauss-Markov noise against
white, by Whittle's approximation.

The lag-1 autocorrelation sees a short correlation time; a long one (30 s at 1 Hz) spreads over many
lags, where the white model's fitted walk absorbs much of it at lag 1, and slow signatures (bias
drift, a rate-dependent error) out-scored it. A test summing the autocorrelations over many lags
(the locally most powerful one, tried first) has the opposite fault: its chi-square grows as the
square of a left-out deterministic effect's energy, where that effect's own score test grows as the
energy, so any large systematic error was named as noise (a symmetric model's misfit on the default
campaign scored log10 p = -40 982 against -125 for the best effect). The likelihood ratio is in the
deterministic candidates' currency: its gain from a systematic error grows only as the log of its
energy, while a Gauss-Markov error's grows with the number of samples it spans.

Whittle's log-likelihood of a stationary series with spectral density f is
``-1/2 sum_j (log f(w_j) + I(w_j) / f(w_j))`` over the Fourier frequencies, I the periodogram. The
model is ``f = sigma^2 ((1 - s) + s f_phi)``, ``f_phi(w) = (1 - phi^2) / (1 - 2 phi cos w + phi^2)``
the unit-variance first-order Gauss-Markov (AR(1)) spectrum at the sampling interval; sigma^2 is
profiled, s and phi are searched on a grid; the likelihood ratio against ``f = sigma^2`` is scored
as a chi-square on two degrees of freedom. It uses the first channel set's innovations: the
whitening leaves the star tracker's error there, the other sets' being the gyros' differences (an
independent review measured their summed autocorrelations at 0.0 against 2.6-3.1).
"""

import numpy as np

__all__ = ["GAUSS_MARKOV_DF", "SHARE_GRID", "TAU_GRID_SAMPLES", "caveat", "periodogram", "score", "whittle_gain"]

TAU_GRID_SAMPLES = np.geomspace(0.5, 500.0, 19)
"""Correlation times searched, in sampling intervals (phi = exp(-1/tau))."""

SHARE_GRID = np.linspace(0.05, 0.95, 19)
"""Gauss-Markov shares of the innovations' variance searched."""

GAUSS_MARKOV_DF = 2
"""Degrees of freedom of the likelihood ratio: the share and the correlation time."""


def periodogram(w: np.ndarray, stride: int, values: int = 3) -> tuple:
    """The periodogram ``|FFT|^2 / m`` of each of a sample's first ``values`` innovation series (of ``w``,
    ``stride`` values per sample) at the Fourier frequencies strictly between 0 and pi, and those
    frequencies (rad per sample), flattened over the series."""
    series = np.asarray(w, dtype=float).reshape(-1, stride)[:, :values]
    m = len(series)
    k = np.arange(1, (m - 1) // 2 + 1)
    power = np.abs(np.fft.rfft(series, axis=0)[k]) ** 2 / m
    return power.ravel(), np.repeat(2 * np.pi * k / m, series.shape[1])


def whittle_gain(power: np.ndarray, omega: np.ndarray) -> tuple:
    """The largest Whittle likelihood ratio (twice the log-likelihood gain) of white plus Gauss-Markov
    over white, with sigma^2 profiled, on the `SHARE_GRID` x `TAU_GRID_SAMPLES` grid; and its share and
    correlation time (samples)."""
    n = len(power)
    if n == 0:
        return 0.0, 0.0, 0.0
    white = n * np.log(np.mean(power))
    phi = np.exp(-1.0 / TAU_GRID_SAMPLES)[:, None]
    shape = (1 - phi**2) / (1 - 2 * phi * np.cos(omega)[None, :] + phi**2)
    best = (0.0, 0.0, 0.0)
    for s in SHARE_GRID:
        g = (1 - s) + s * shape
        gain = white - n * np.log(np.mean(power / g, axis=1)) - np.sum(np.log(g), axis=1)
        i = int(np.argmax(gain))
        if gain[i] > best[0]:
            best = (float(gain[i]), float(s), float(TAU_GRID_SAMPLES[i]))
    return best


def score(parts) -> dict:
    """The likelihood ratio over pooled periodograms ``parts`` ((power, omega) per maneuver, `periodogram`),
    with its share, correlation time (samples) and ``log10_p`` (chi-square on `GAUSS_MARKOV_DF`, two:
    ``P(chi2_2 > x) = e^(-x/2)``)."""
    power = np.concatenate([p for p, _ in parts])
    omega = np.concatenate([o for _, o in parts])
    gain, share, tau = whittle_gain(power, omega)
    return {"chi2": round(gain, 2), "share": round(share, 2), "tau_samples": round(tau, 2),
            "log10_p": round(-gain / 2 / np.log(10), 2)}


def caveat(fitted: dict) -> str:
    """What the ranking adds to the noise's description where its correlation time is at the search's
    end (`TAU_GRID_SAMPLES`): there a slow systematic error fits as well, such as one of the channel
    model's own terms that the model lacks (a symmetric scale factor on asymmetric data scored log10
    p = -811 as noise on the default campaign, where no candidate is the asymmetry)."""
    if fitted["chi2"] <= 0 or fitted["tau_samples"] < TAU_GRID_SAMPLES[-1]:
        return ""
    return (f"; here its correlation time is at the search's end ({TAU_GRID_SAMPLES[-1]:g} samples), as long "
            "as the maneuvers, where a slow systematic error that no candidate is fits as well")
