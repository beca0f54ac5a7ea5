"""Correlated star-tracker noise, first-order Gauss-Markov, as an exact banded covariance.

A star tracker's error is white plus a slow part that persists over a correlation time
``tau`` (focal-plane and catalogue errors of the stars in view, a filtered attitude). The
slow part is a first-order Gauss-Markov process in the tracker's frame, which turns with the
spacecraft: ``g_j = phi_j g_(j-1) + nu_j`` with ``phi_j = exp(-dt_j / tau)``, anisotropic about
the boresight like the white part, seen in the inertial frame as ``R_j g_j``. Each channel set's
error series is then white noise plus the gyro's random walk plus the GM: no finite band holds
its covariance, and a taper would bias ``tau``.

The second-order filter ``y_j = x_j + A_j x_(j-1) + B_j x_(j-2)`` with 3x3 coefficients

    A_j = (R_(j-2) - phi_j phi_(j-1) R_j) (phi_(j-1) R_(j-1) - R_(j-2))^-1,   B_j = -I - A_j

ends the memory of both the walk (``I + A + B = 0``) and the GM (the coefficient of ``g_(j-2)``,
``(phi_j R_j + A_j R_(j-1)) phi_(j-1) + B_j R_(j-2)``, vanishes), for any sampling and attitude
(gaps included): the filtered walk is ``xi_j - B_j xi_(j-1)``, the filtered GM
``R_j nu_j + D_j nu_(j-1)`` with ``D_j = phi_j R_j + A_j R_(j-1)``, the filtered white noise a
moving average of three samples. Any white error filters so, whatever its covariance ``U_j`` at each
sample: the reference's timing jitter (``sigma_t^2 R_j omega_j omega_j^T R_j^T``, `covariance`) is one
more such component, linear in ``sigma_t^2``, with no Gauss-Markov counterpart. The filtered series'
covariance is banded two samples deep and linear in the five variances (six with the jitter), and the
filter is unit lower triangular, so the likelihood is that
of the series itself: the banded algebra of `noise` (Cholesky, whitening, selected inverse)
applies unchanged, at a cost linear in the telemetry length whatever tau is. While the attitude
holds, ``A_j`` is the scalar ``-(1 - phi_j phi_(j-1)) / (1 - phi_(j-1))``; at ``tau -> 0``
(``phi = 0``) the filter is the first difference of the white model. Where tau is far beyond the
maneuvers and the attitude turns about changing axes, ``A_j`` grows like rate x tau and the filtered
covariance loses precision (its log-determinant off by 3e-4 at tau 3 000 s slewing 2 deg/s about an
axis that changes every 100 s), then positive definiteness, where the REML's objective is inf
(`noisefit.finite_profile`).
"""

import numpy as np
from scipy.linalg import solve_banded

__all__ = ["COMPONENTS", "Filter", "coefficients", "covariance_blocks", "over_sets"]

COMPONENTS = ("cross", "about", "walk", "gm_cross", "gm_about")
"""The filtered covariance's components, each linear in its own variance: the white star-tracker
noise across and about the boresight, the gyro walk, and the GM across and about the boresight; and
where the reference's timing jitter is modelled, ``jitter`` (`covariance_blocks`' ``white_only``)."""


def _transposed(x: np.ndarray) -> np.ndarray:
    return np.swapaxes(x, -1, -2)


def coefficients(st_dt_s: np.ndarray, tau_s: float, st_matrix: np.ndarray):
    """``(A, B, phi)``: the filter's (M, 3, 3) coefficients and ``phi`` per star-tracker sample, for
    the tracker's attitudes ``st_matrix`` (M, 3, 3, tracker to inertial). ``phi_0 = 0`` (the GM starts
    stationary) and the second sample is first-differenced (``A_1 = -I``), which keeps it finite.
    Taken relative to ``R_(j-2)``, with ``1 - phi`` from ``expm1``, the coefficients keep their
    precision for ``tau`` far beyond the sampling interval."""
    m = len(st_dt_s)
    one_minus = np.ones(m)
    one_minus[1:] = -np.expm1(-np.asarray(st_dt_s[1:], dtype=float) / tau_s)
    phi = 1.0 - one_minus
    eye = np.eye(3)
    a, b = np.zeros((m, 3, 3)), np.zeros((m, 3, 3))
    if m > 1:
        a[1] = -eye
    if m > 2:
        r = np.asarray(st_matrix, dtype=float)
        base_t = _transposed(r[:-2])
        turned = base_t @ r[2:]
        turned_half = base_t @ r[1:-1]
        p, p_prev = phi[2:, None, None], phi[1:-1, None, None]
        numerator = (one_minus[2:] + phi[2:] * one_minus[1:-1])[:, None, None] * eye + p * p_prev * (eye - turned)
        denominator = -one_minus[1:-1, None, None] * eye - p_prev * (eye - turned_half)
        relative = _transposed(np.linalg.solve(_transposed(denominator), _transposed(numerator)))
        a[2:] = r[:-2] @ relative @ base_t
        b[2:] = -eye - a[2:]
    return a, b, phi


class Filter:
    """The filter ``T`` of one series over time-major rows: per sample its channel sets' three axes
    (``n_sets`` x 3 rows, set-major), each set filtered alike."""

    def __init__(self, a: np.ndarray, b: np.ndarray, n_sets: int):
        self.a, self.b, self.n_sets = a, b, n_sets

    def _sets(self, x: np.ndarray) -> np.ndarray:
        """``x`` (M, S, 3, ...) or (M, 3 S, ...) as (M, S, 3, K)."""
        return np.asarray(x, dtype=float).reshape(len(x), self.n_sets, 3, -1)

    def apply(self, x: np.ndarray) -> np.ndarray:
        """``T x`` along the first (time) axis of ``x``."""
        v = self._sets(x)
        y = v.copy()
        y[1:] += self.a[1:, None] @ v[:-1]
        y[2:] += self.b[2:, None] @ v[:-2]
        return y.reshape(np.shape(x))

    def transpose(self, y: np.ndarray) -> np.ndarray:
        """``T^T y`` along the first axis."""
        v = self._sets(y)
        x = v.copy()
        x[:-1] += _transposed(self.a[1:])[:, None] @ v[1:]
        x[:-2] += _transposed(self.b[2:])[:, None] @ v[2:]
        return x.reshape(np.shape(y))

    def invert(self, y: np.ndarray) -> np.ndarray:
        """``T^-1 y`` along the first axis: one banded triangular solve over (sample, axis) rows
        (LAPACK), every set and column at once."""
        m = len(self.a)
        v = self._sets(y)
        flat = v.transpose(0, 2, 1, 3).reshape(3 * m, -1)
        ab = np.zeros((9, 3 * m))
        ab[0] = 1.0
        for row in range(3):
            for col in range(3):
                cols = 3 * np.arange(m) + col
                ab[3 + row - col, cols[:-1]] = self.a[1:, row, col]
                ab[6 + row - col, cols[:-2]] = self.b[2:, row, col]
        x = solve_banded((8, 0), ab, flat)
        return x.reshape(m, 3, self.n_sets, -1).transpose(0, 2, 1, 3).reshape(np.shape(y))

    def columns(self, start: int, stop: int) -> np.ndarray:
        """``T[start:end, start:stop]`` as a dense array, ``end`` two samples past ``stop`` (or the
        series' end): every row where those columns of T are not zero (`predictive`)."""
        width = 3 * self.n_sets
        first, last = start // width, min(-(-stop // width) + 2, len(self.a))
        unit = np.zeros(((last - first) * width, stop - start))
        unit[np.arange(start, stop) - first * width, np.arange(stop - start)] = 1.0
        window = Filter(self.a[first:last], self.b[first:last], self.n_sets)
        return window.apply(unit.reshape(last - first, width, -1)).reshape(len(unit), -1)[start - first * width:]


def _lagged(u: np.ndarray, k: int) -> np.ndarray:
    """``u[j - k]`` per sample j, zero where ``j - k < 0``."""
    out = np.zeros_like(u)
    if k < len(u):
        out[k:] = u[:len(u) - k]
    return out


def over_sets(pattern: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(M, 3, 3) blocks laid over the channel sets as (M, 3 S, 3 S), set ``(s, t)`` getting
    ``pattern[s, t]`` times the block: ones for the star tracker's error, shared by every pair of
    sets; the identity for a filter that acts on every set alike."""
    n_sets = len(pattern)
    return np.einsum("st,jab->jsatb", pattern, u).reshape(len(u), 3 * n_sets, 3 * n_sets)


def _filtered_white(u, a, b, a_t, b_t, a_prev_t, ones):
    """White noise of per-sample covariance ``u`` (M, 3, 3), shared by the sets, through the filter: a
    moving average of three samples, its diagonal blocks and those one and two samples below them."""
    u1, u2 = _lagged(u, 1), _lagged(u, 2)
    diag = u + a @ u1 @ a_t + b @ u2 @ b_t
    lag1 = a @ u1 + b @ u2 @ a_prev_t
    lag2 = b @ u2
    return tuple(over_sets(ones, x) for x in (diag, lag1, lag2))


def covariance_blocks(st_matrix: np.ndarray, body_shapes: dict, walk: np.ndarray, st_dt_s: np.ndarray,
                      tau_s: float, n_sets: int, walk_lag1=None, white_only=None):
    """Per component, the filtered covariance's diagonal blocks (M, B, B) and the blocks one and
    two samples below them, per unit variance (B = 3 x sets). ``body_shapes`` maps ``cross`` and
    ``about`` to the tracker-frame 3x3 covariance shapes, each white with a Gauss-Markov counterpart
    (``gm_cross``, ``gm_about``); ``white_only`` maps more white components without one to their
    (M, 3, 3) per-sample shapes (the timing jitter's ``omega omega^T``, `covariance.jitter_shapes`).
    ``walk`` is (M, S, S, 3, 3), each interval's walk covariance per unit ARW^2, ``walk_lag1`` (M,)
    the walk shared by step j with step j - 1 where star-tracker samples fall inside gyro intervals
    (`errormodel.walk_steps`). Returns ``(blocks, filter)``."""
    a, b, phi = coefficients(st_dt_s, tau_s, st_matrix)
    r = np.asarray(st_matrix, dtype=float)
    ones = np.ones((n_sets, n_sets))
    a_t, b_t = _transposed(a), _transposed(b)
    a_prev_t = _lagged(a_t, 1)
    d = np.zeros_like(a)
    d[1:] = phi[1:, None, None] * r[1:] + a[1:] @ r[:-1]
    r_prev_t = _lagged(_transposed(r), 1)
    innovation = (1.0 - phi**2)[:, None, None]
    blocks = {}
    for name, shape in body_shapes.items():
        blocks[name] = _filtered_white(r @ shape @ _transposed(r), a, b, a_t, b_t, a_prev_t, ones)
        v = innovation * shape
        v1 = _lagged(v, 1)
        gm_diag = r @ v @ _transposed(r) + d @ v1 @ _transposed(d)
        blocks[f"gm_{name}"] = tuple(over_sets(ones, x) for x in (gm_diag, d @ v1 @ r_prev_t, np.zeros_like(v)))
    for name, shapes in (white_only or {}).items():
        blocks[name] = _filtered_white(r @ shapes @ _transposed(r), a, b, a_t, b_t, a_prev_t, ones)
    m = len(st_dt_s)
    w = walk.transpose(0, 1, 3, 2, 4).reshape(m, 3 * n_sets, 3 * n_sets)
    w1 = _lagged(w, 1)
    c = over_sets(np.eye(n_sets), np.eye(3) + a)
    c_t = _transposed(c)
    if walk_lag1 is None:
        blocks["walk"] = (w + c @ w1 @ c_t, c @ w1, np.zeros_like(w))
    else:  # y_j = D_j + C_j D_(j-1), with Cov(D_j, D_(j-1)) = s_j I
        s = np.asarray(walk_lag1, dtype=float)[:, None, None]
        s1 = _lagged(s, 1)
        eye = np.eye(3 * n_sets)
        blocks["walk"] = (w + c @ w1 @ c_t + s * (c + c_t), s * eye + c @ w1 + s1 * (c @ _lagged(c_t, 1)), s1 * c)
    return blocks, Filter(a, b, n_sets)
