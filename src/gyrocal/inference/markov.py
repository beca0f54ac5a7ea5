"""Correlated star-tracker noise, first-order Gauss-Markov, as an exact banded covariance.

A star tracker's error is white plus a slow part that persists over a correlation time
``tau`` (focal-plane and catalogue errors of the stars in view, a filtered attitude). The
slow part is a first-order Gauss-Markov process in the inertial frame,
``g_j = phi_j g_(j-1) + nu_j`` with ``phi_j = exp(-dt_j / tau)``, whose innovations ``nu_j``
are anisotropic about the boresight like the white part (``R_j`` times a tracker-frame
covariance). Each channel set's error series is then white noise plus the gyro's random walk
plus the GM: no finite band holds its covariance, and a taper would bias ``tau``.

The second-order filter ``y_j = x_j + alpha_j x_(j-1) + beta_j x_(j-2)`` with

    alpha_j = -(1 - phi_j phi_(j-1)) / (1 - phi_(j-1)),   beta_j = phi_(j-1) (1 - phi_j) / (1 - phi_(j-1))

ends the memory of both the walk (``1 + alpha + beta = 0``) and the GM, for any sampling
(gaps included): the filtered walk is ``xi_j - beta_j xi_(j-1)``, the filtered GM
``nu_j + d_j nu_(j-1)`` with ``d_j = -(1 - phi_j) / (1 - phi_(j-1))``, the filtered white noise
a moving average of three samples. The filtered series' covariance is banded two samples
deep and linear in the five variances, and the filter is unit lower triangular, so the
likelihood is that of the series itself: the banded algebra of `noise` (Cholesky, whitening,
selected inverse) applies unchanged, at a cost linear in the telemetry length whatever tau is.
At ``tau -> 0`` (``phi = 0``) the filter is the first difference of the white model.
"""

import numpy as np
from scipy.linalg import solve_banded

__all__ = ["COMPONENTS", "Filter", "coefficients", "covariance_blocks"]

COMPONENTS = ("cross", "about", "walk", "gm_cross", "gm_about")
"""The filtered covariance's components, each linear in its own variance: the white star-tracker
noise across and about the boresight, the gyro walk, and the GM across and about the boresight."""


def coefficients(st_dt_s: np.ndarray, tau_s: float):
    """``(alpha, beta, phi)`` per star-tracker sample; ``phi_0 = 0`` (the GM starts stationary)
    and the second sample is first-differenced (``alpha_1 = -1``), which keeps it finite."""
    m = len(st_dt_s)
    one_minus = np.ones(m)
    one_minus[1:] = -np.expm1(-np.asarray(st_dt_s[1:], dtype=float) / tau_s)
    phi = 1.0 - one_minus
    alpha, beta = np.zeros(m), np.zeros(m)
    if m > 1:
        alpha[1] = -1.0
    alpha[2:] = -(one_minus[2:] + phi[2:] * one_minus[1:-1]) / one_minus[1:-1]
    beta[2:] = phi[1:-1] * one_minus[2:] / one_minus[1:-1]
    return alpha, beta, phi


class Filter:
    """The filter ``T`` of one maneuver over time-major rows (``width`` rows per sample)."""

    def __init__(self, alpha: np.ndarray, beta: np.ndarray):
        self.alpha, self.beta = alpha, beta

    def _lags(self, x):
        return (self.alpha[:, None], self.beta[:, None]) if x.ndim == 2 else (
            self.alpha.reshape((-1,) + (1,) * (x.ndim - 1)), self.beta.reshape((-1,) + (1,) * (x.ndim - 1)))

    def apply(self, x: np.ndarray) -> np.ndarray:
        """``T x`` along the first (time) axis of ``x`` (M, ...)."""
        a, b = self._lags(x)
        y = np.array(x, dtype=float, copy=True)
        y[1:] += a[1:] * x[:-1]
        y[2:] += b[2:] * x[:-2]
        return y

    def transpose(self, y: np.ndarray) -> np.ndarray:
        """``T^T y`` along the first axis."""
        a, b = self._lags(y)
        x = np.array(y, dtype=float, copy=True)
        x[:-1] += a[1:] * y[1:]
        x[:-2] += b[2:] * y[2:]
        return x

    def invert(self, y: np.ndarray) -> np.ndarray:
        """``T^-1 y`` along the first axis: a banded triangular solve (LAPACK), all columns at once."""
        m = len(self.alpha)
        ab = np.zeros((3, m))
        ab[0] = 1.0
        ab[1, :-1] = self.alpha[1:]
        ab[2, :-2] = self.beta[2:]
        flat = y.reshape(m, -1)
        return solve_banded((2, 0), ab, flat).reshape(y.shape)

    def row_coefficients(self, width: int):
        """``(t1, t2)`` per row of the flattened series: ``T[r + width, r]`` and ``T[r + 2 width, r]``
        (zero past the end), what `predictive` needs for ``T^T Z T``."""
        m = len(self.alpha)
        t1, t2 = np.zeros(m), np.zeros(m)
        t1[:-1], t2[:-2] = self.alpha[1:], self.beta[2:]
        return np.repeat(t1, width), np.repeat(t2, width)


def _lagged(u: np.ndarray, k: int) -> np.ndarray:
    """``u[j - k]`` per sample j, zero where ``j - k < 0``."""
    out = np.zeros_like(u)
    if k < len(u):
        out[k:] = u[:len(u) - k]
    return out


def covariance_blocks(st_matrix: np.ndarray, body_shapes: dict, walk: np.ndarray, st_dt_s: np.ndarray,
                      tau_s: float, n_sets: int, walk_lag1=None):
    """Per component, the filtered covariance's diagonal blocks (M, B, B) and the blocks one and
    two samples below them, per unit variance (B = 3 x sets). ``body_shapes`` maps ``cross`` and
    ``about`` to the tracker-frame 3x3 covariance shapes; ``walk`` is (M, S, S, 3, 3), each
    interval's walk covariance per unit ARW^2, ``walk_lag1`` (M,) the walk shared by step j with
    step j - 1 where star-tracker samples fall inside gyro intervals (`errormodel.walk_steps`).
    Returns ``(blocks, filter)``."""
    alpha, beta, phi = coefficients(st_dt_s, tau_s)
    m = len(st_dt_s)
    ones = np.ones((n_sets, n_sets))

    def shared(u):
        """3x3 blocks shared by every pair of channel sets (the star tracker's, one for all)."""
        return np.einsum("st,jab->jsatb", ones, u).reshape(len(u), 3 * n_sets, 3 * n_sets)

    a = alpha[:, None, None]
    b = beta[:, None, None]
    a_prev = _lagged(alpha, 1)[:, None, None]
    innovation = (1.0 - phi**2)[:, None, None]
    d = np.zeros(m)
    d[1:] = phi[1:] + alpha[1:]
    d = d[:, None, None]
    blocks = {}
    for name, shape in body_shapes.items():
        u = np.einsum("jab,bc,jdc->jad", st_matrix, shape, st_matrix)
        u1, u2 = _lagged(u, 1), _lagged(u, 2)
        diag = u + a**2 * u1 + b**2 * u2
        lag1 = a * u1 + b * a_prev * u2
        lag2 = b * u2
        blocks[name] = tuple(shared(x) for x in (diag, lag1, lag2))
        v = innovation * u
        v1 = _lagged(v, 1)
        blocks[f"gm_{name}"] = tuple(shared(x) for x in (v + d**2 * v1, d * v1, np.zeros_like(v)))
    w = walk.transpose(0, 1, 3, 2, 4).reshape(m, 3 * n_sets, 3 * n_sets)
    w1 = _lagged(w, 1)
    c = np.zeros(m)
    c[1:] = 1.0 + alpha[1:]
    c_prev = _lagged(c, 1)[:, None, None]
    c = c[:, None, None]
    if walk_lag1 is None:
        blocks["walk"] = (w + c**2 * w1, c * w1, np.zeros_like(w))
    else:  # y_j = D_j + c_j D_(j-1), with Cov(D_j, D_(j-1)) = shared_j
        shared = np.asarray(walk_lag1, dtype=float)[:, None, None] * np.eye(3 * n_sets)
        shared1 = _lagged(shared, 1)
        blocks["walk"] = (w + c**2 * w1 + 2 * c * shared, shared + c * w1 + c * c_prev * shared1, c * shared1)
    return blocks, Filter(alpha, beta)
