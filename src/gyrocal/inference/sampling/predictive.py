"""Residuals, pointwise log-likelihood and posterior-predictive draws of the attitude error.

These evaluate the sampled posterior against the data: per draw the nuisance
(initial attitude error, biases) is set to its conditional least-squares value, the
residual is formed in the inertial frame and rotated into body axes, and noise
replicates come from the banded covariance of `noise`.
"""

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_solve_banded, solve_triangular

from gyrocal.inference.errormodel import Linearization
from gyrocal.inference.noise.covariance import ManeuverNoise, nuisance_design, ratios_of, unit_variances, untransformed
from gyrocal.inference.noise.selectedinverse import inverse_windows, recursion_bounds

__all__ = [
    "MIN_REST_SAMPLES", "PARETO_K_MAX", "BlockConditional", "WhitenedManeuver", "block_conditionals", "block_index",
    "gauss_markov_draws", "leave_block_out_loglik", "maneuver_block_s", "residuals_body", "sample_blocks", "split_draws",
    "undifference_body",
]

PARETO_K_MAX = 0.7
"""Above this Pareto k a block's PSIS-LOO estimate is unreliable (Vehtari et al. 2017): the
posterior's importance weights for that block, from these pointwise log-likelihoods, have too
heavy a tail."""


class WhitenedManeuver:
    """One maneuver whitened at fixed noise ratios (unit cross-boresight variance)."""

    def __init__(self, noise: ManeuverNoise, ratios):
        self.noise = noise
        self.chol = noise.factor(unit_variances(ratios))
        self.white = noise.whiten(self.chol, noise.rhs)
        p, g = noise.n_params, noise.n_nuisance
        self.wx, self.wg, self.wd = self.white[:, :p], self.white[:, p:p + g], self.white[:, -1]
        self.gram_g = self.wg.T @ self.wg

    def nuisance(self, dtheta: np.ndarray) -> np.ndarray:
        """(D, G) conditional least-squares nuisance for each row of ``dtheta``."""
        target = self.wd[:, None] - self.wx @ dtheta.T
        return np.linalg.solve(self.gram_g, self.wg.T @ target).T

    def noise_draws(self, scale, rng) -> np.ndarray:
        """(D, n) differenced noise replicates ``sqrt(scale) L xi``."""
        xi = rng.standard_normal((len(scale), self.chol.shape[1]))
        out = np.zeros_like(xi)
        n = xi.shape[1]
        for k in range(self.chol.shape[0]):
            out[:, k:] += self.chol[k, :n - k] * xi[:, :n - k]
        return out * np.sqrt(scale)[:, None]


def gauss_markov_draws(steps_s, tau_s: float, boresight_body, var_cross, var_about, n_sets: int, rng) -> np.ndarray:
    """(D, M, S, 3) replicates of the reference error's Gauss-Markov part in the tracker's axes, as
    `undifference_body` gives a series (shared by the S channel sets), drawn as the process itself:
    ``g_j = phi_j g_(j-1) + sqrt(1 - phi_j^2) nu_j``, stationary from the first sample, on its clock's
    ``steps_s``, with per-draw variances ``var_cross`` about each axis across ``boresight_body`` and
    ``var_about`` about it (D,). The filter's inverse, which the likelihood never needs, loses its
    precision where tau is far beyond the steps (`markov`: an angle clock at rest), so the predictive
    band is drawn from the process, not back through the filter. A loop over the samples (a recursion),
    every draw at once."""
    b = np.asarray(boresight_body, dtype=float)
    b = b / np.linalg.norm(b)
    u = np.cross(b, [1.0, 0.0, 0.0] if abs(b[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    basis = np.stack([u, np.cross(b, u), b])  # rows: the two axes across the boresight, then it
    sd = np.sqrt(np.stack([var_cross, var_cross, var_about], axis=-1))  # (D, 3)
    steps = np.asarray(steps_s, dtype=float)
    phi = np.exp(-steps / tau_s)
    phi[0] = 0.0
    innovation = np.sqrt(-np.expm1(-2.0 * steps / tau_s))
    innovation[0] = 1.0
    xi = rng.standard_normal((len(sd), len(phi), 3)) * sd[:, None, :]
    g = np.empty_like(xi)
    g[:, 0] = xi[:, 0]
    for j in range(1, len(phi)):
        g[:, j] = phi[j] * g[:, j - 1] + innovation[j] * xi[:, j]
    return np.broadcast_to((g @ basis)[:, :, None, :], (len(sd), len(phi), n_sets, 3))


def residuals_body(lin: Linearization, dtheta: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """(D, M, S, 3) star tracker minus model, in body axes (rad), per draw."""
    nuis = nuisance_design(lin)
    fitted = lin.design.reshape(-1, dtheta.shape[1]) @ dtheta.T + nuis.reshape(-1, beta.shape[1]) @ beta.T
    resid = lin.z[None] - fitted.T.reshape((len(dtheta),) + lin.z.shape)
    return resid @ lin.st_matrix[None]  # row vectors times R: R^T r, inertial to body


def undifference_body(lin: Linearization, differenced: np.ndarray, nz: ManeuverNoise | None = None) -> np.ndarray:
    """(D, M, S, 3) body-axis series from transformed inertial series (D, n): first differences,
    or the Gauss-Markov filter of ``nz``."""
    m, s = lin.z.shape[:2]
    series = np.moveaxis(differenced.reshape(len(differenced), m, s, 3), 1, 0)
    inertial = np.moveaxis(untransformed(series, None if nz is None else nz.filter), 0, 1)
    return inertial @ lin.st_matrix[None]


MIN_REST_SAMPLES = 10
"""Star-tracker samples of a maneuver that must remain when any one leave-one-block-out block is
left out: fewer cannot pin down the maneuver's nuisance (initial attitude and biases)."""


def maneuver_block_s(st_time, block_s) -> float | None:
    """The block length of one maneuver: ``block_s``, halved until `MIN_REST_SAMPLES` star-tracker
    samples lie outside its largest block (a maneuver shorter than two blocks, as the pieces of a
    hand-held recording cut at its rests); None where no block of two samples or more leaves them."""
    st_time = np.asarray(st_time, dtype=float)
    step = float(np.median(np.diff(st_time))) if len(st_time) > 1 else np.inf
    block = float(block_s)
    while block >= 2 * step:
        if len(st_time) - np.bincount(_block_numbers(st_time, block)).max() >= MIN_REST_SAMPLES:
            return block
        block /= 2
    return None


def _block_numbers(st_time, block_s) -> np.ndarray:
    """Block number of each sample, blocks of ``block_s`` seconds from the first."""
    return np.floor((st_time - st_time[0]) / block_s).astype(int)


def sample_blocks(st_time, block_s) -> np.ndarray:
    """Block number of each star-tracker sample: `maneuver_block_s` seconds from the maneuver's first
    (``block_s`` where the maneuver is long enough for it)."""
    return _block_numbers(st_time, maneuver_block_s(st_time, block_s) or float(block_s))


def block_index(lin: Linearization, st_time, block_s) -> np.ndarray:
    """Block number of each whitened row (time-major, then set, then axis)."""
    per_time = lin.z.shape[1] * 3
    return np.repeat(sample_blocks(st_time, block_s), per_time)


def split_draws(flat: np.ndarray, n_params: int, n_noise: int | None = None):
    """``(dtheta, ratios, scale)`` of draws ``[dtheta (P), log sigma_cross, log sigma_about, log arw]``
    (``n_noise`` noise scales; whatever follows them, the noise groups', is the caller's): the
    pointwise terms are whitened once, at the draws' mean noise ratios (a factor per draw would
    repeat the banded inversion per draw), while ``scale = sigma_cross^2`` is each draw's own (it
    enters in closed form)."""
    stop = None if n_noise is None else n_params + n_noise
    dtheta, log_sigma = flat[:, :n_params], flat[:, n_params:stop]
    ratios = np.mean(ratios_of(log_sigma), axis=0)
    return dtheta, ratios, np.exp(2 * log_sigma[:, 0])


def _undifference_transpose(x: np.ndarray, block: int) -> np.ndarray:
    """``T^T x`` for the first-difference transform T over time blocks of ``block`` rows."""
    out = x.copy()
    out[:-block] -= x[block:]
    return out


@dataclass
class BlockConditional:
    """One block's density given every other row of its maneuver, as a whitened linear system.

    ``log p(y_b | y_-b, dtheta, scale) = 1/2 logdet - n_b/2 log(2 pi scale) - 1/2 |r - W dtheta|^2 / scale``
    with ``W = w[:, :P]`` and ``r = w[:, -1]``: quadratic in the draw, so its curvature in the
    parameters (``W' W / scale``) is exact, which `looexact` uses to explain p_loo.
    """

    block: int
    logdet: float
    """``log |Prec_bb|`` at unit scale."""
    w: np.ndarray
    """(n_b, P + 1) ``F^-1 (Prec [X, y])_b`` with ``F F' = Prec_bb``, Prec the precision of the
    undifferenced series with the nuisance projected out: the design's columns, then the data's."""

    def loglik(self, dtheta: np.ndarray, scale) -> np.ndarray:
        """(D,) the density's log at each row of ``dtheta`` with its ``scale`` (sigma_cross^2)."""
        p = dtheta.shape[1]
        quad = np.sum((self.w[:, -1:] - self.w[:, :p] @ dtheta.T) ** 2, axis=0)
        return 0.5 * (self.logdet - len(self.w) * np.log(2 * np.pi * scale)) - 0.5 * quad / scale


def block_conditionals(lin: Linearization, whitened: WhitenedManeuver, block_of_row):
    """Yield a `BlockConditional` per non-empty block: ``log p(block | all other data, draw)``
    with the nuisance integrated out.

    For a Gaussian with precision P, ``log p(y_b | y_-b) = 1/2 log|P_bb| - n_b/2 log 2 pi
    - 1/2 (P r)_b' P_bb^-1 (P r)_b``, and ``P r`` is linear in the draw; with a flat-prior
    nuisance G the precision is ``P = Q - QG (G'QG)^-1 G'Q``. Q is the inverse of the undifferenced covariance,
    ``T' C^-1 T`` with C the banded covariance of the differenced series, so ``Q_bb``
    needs ``C^-1`` over the block and the ``width`` rows after it: `selectedinverse`
    gives those in time linear in the telemetry length. The noise ratios are those
    ``whitened`` was factored at (unit sigma_cross).
    """
    chol, noise = whitened.chol, whitened.noise
    width = lin.z.shape[1] * 3
    n, p, g = noise.n, noise.n_params, noise.n_nuisance

    def q_apply(differenced):
        solved = cho_solve_banded((chol, True), differenced)
        if noise.filter is None:
            return _undifference_transpose(solved, width)
        return noise.filter.transpose(solved.reshape(-1, width, solved.shape[1])).reshape(solved.shape)

    q_all = q_apply(noise.rhs)
    q_g = q_all[:, p:p + g]
    g_und = nuisance_design(lin).reshape(n, g)
    gqg_inv = np.linalg.inv(g_und.T @ q_g)
    projected = np.delete(q_all, np.s_[p:p + g], axis=1)
    projected -= q_g @ (gqg_inv @ (g_und.T @ projected))
    n_blocks = block_of_row.max() + 1
    first_row = np.searchsorted(block_of_row, np.arange(n_blocks + 1))
    edges = recursion_bounds(np.unique(first_row), chol.shape[0] - 1)
    home = np.searchsorted(edges, first_row[:-1], side="right") - 1
    for start, z in inverse_windows(chol, edges):
        for b in np.flatnonzero((edges[home] == start) & (first_row[1:] > first_row[:-1])):
            rows = slice(first_row[b], first_row[b + 1])
            if noise.filter is None:
                q_bb = _undifferenced_block(z, rows.start - start, rows.stop - start, width, n - start)
            else:
                q_bb = _filtered_block(z, rows.start - start, noise.filter.columns(rows.start, rows.stop))
            p_bb = q_bb - q_g[rows] @ gqg_inv @ q_g[rows].T
            factor = np.linalg.cholesky(p_bb)
            logdet = 2 * np.sum(np.log(np.diag(factor)))
            yield BlockConditional(int(b), logdet, solve_triangular(factor, projected[rows], lower=True))


def leave_block_out_loglik(lin: Linearization, whitened: WhitenedManeuver, dtheta, scale, block_of_row):
    """(D, n_blocks) ``log p(block | all other data, draw)`` with the nuisance integrated out
    (`block_conditionals`); the scale (sigma_cross^2) is per draw. These are the pointwise
    terms PSIS-LOO needs (one-step-ahead terms are not)."""
    out = np.zeros((len(dtheta), block_of_row.max() + 1))
    for term in block_conditionals(lin, whitened, block_of_row):
        out[:, term.block] = term.loglik(dtheta, scale)
    return out


def _undifferenced_block(z, i0, i1, width, n_local):
    """``(T' Z T)[i0:i1, i0:i1]`` from a window ``z`` of ``Z = C^-1`` that reaches ``width`` rows
    past ``i1`` (or the end of the series, ``n_local``): T's column j is ``e_j - e_(j+width)``."""
    q = z[i0:i1, i0:i1].copy()
    v = int(np.clip(n_local - width - i0, 0, i1 - i0))
    q[:v] -= z[i0 + width:i0 + width + v, i0:i1]
    q[:, :v] -= z[i0:i1, i0 + width:i0 + width + v]
    q[:v, :v] += z[i0 + width:i0 + width + v, i0 + width:i0 + width + v]
    return q


def _filtered_block(z, i0, columns):
    """``(T' Z T)[i0:i1, i0:i1]`` for a Gauss-Markov filter T, from its ``columns`` i0..i1 over every
    row where they are not zero (`markov.Filter.columns`), which the window ``z`` reaches."""
    span = slice(i0, i0 + len(columns))
    return columns.T @ z[span, span] @ columns
