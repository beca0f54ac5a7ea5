"""Diagonal blocks of the inverse of a banded covariance, in time linear in its size.

The leave-one-block-out predictive densities need the precision of the data on each
block, which is a block of ``C^-1`` for the banded covariance ``C`` of `noise`. ``C^-1``
is dense, so solving for it column by column costs O(n^2) in the telemetry length.
Takahashi's recursion (Takahashi, Fagan & Chin 1973; Rue & Martino 2007, section 2)
gives the blocks near the diagonal from the banded Cholesky factor alone: with ``L``
block lower bidiagonal over contiguous blocks no shorter than its bandwidth, ``L^T Z =
L^-1`` for ``Z = C^-1`` yields, from the last block back,

    Z[k+1, k] = -Z[k+1, k+1] L[k+1, k] L[k, k]^-1
    Z[k, k]   =  L[k, k]^-T (L[k, k]^-1 - L[k+1, k]^T Z[k+1, k])

at O(m^3) per block of m rows. scipy has banded factors and solves, but no selected
inversion, hence this module.
"""

from itertools import pairwise

import numpy as np
from scipy.linalg import solve_triangular


def band_block(chol: np.ndarray, rows: slice, cols: slice) -> np.ndarray:
    """Dense ``L[rows, cols]`` of a lower band-stored factor (``chol[d, j] = L[j + d, j]``)."""
    i = np.arange(rows.start, rows.stop)[:, None]
    j = np.arange(cols.start, cols.stop)[None, :]
    d = i - j
    inside = (d >= 0) & (d < chol.shape[0])
    return np.where(inside, chol[np.clip(d, 0, chol.shape[0] - 1), j], 0.0)


def recursion_bounds(bounds: np.ndarray, bandwidth: int) -> np.ndarray:
    """Block edges no closer than ``bandwidth`` (but the last block), so that ``L`` is block
    bidiagonal over them: a short block is merged into the one after it."""
    edges = [int(bounds[0])]
    for b in bounds[1:-1]:
        if b - edges[-1] >= bandwidth:
            edges.append(int(b))
    if bounds[-1] - edges[-1] < bandwidth and len(edges) > 1:
        edges.pop()
    return np.array(edges + [int(bounds[-1])])


def inverse_windows(chol: np.ndarray, bounds: np.ndarray):
    """Yield ``(start, Z)`` per block of ``bounds``, last first: ``Z = C^-1[start:stop, start:stop]``
    over the block and the one after it (``stop`` is the end of that next block, or n).

    ``bounds`` are block edges from 0 to n, every block but the last at least the factor's
    bandwidth long (`recursion_bounds`).
    """
    if bounds[0] != 0 or bounds[-1] != chol.shape[1]:
        raise ValueError(f"block edges must run from 0 to {chol.shape[1]}, got {bounds[0]} to {bounds[-1]}")
    blocks = [slice(int(a), int(b)) for a, b in pairwise(bounds)]
    last = blocks[-1]
    inv_last = solve_triangular(band_block(chol, last, last), np.eye(last.stop - last.start), lower=True)
    z_next = inv_last.T @ inv_last
    yield last.start, z_next
    for k in range(len(blocks) - 2, -1, -1):
        here, after = blocks[k], blocks[k + 1]
        inv_kk = solve_triangular(band_block(chol, here, here), np.eye(here.stop - here.start), lower=True)
        below = band_block(chol, after, here)
        z_below = -z_next @ below @ inv_kk
        z_here = inv_kk.T @ (inv_kk - below.T @ z_below)
        yield here.start, np.block([[z_here, z_below.T], [z_below, z_next]])
        z_next = z_here
