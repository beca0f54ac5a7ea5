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
from scipy.linalg.lapack import dtrtri

__all__ = ["band_block", "inverse_windows", "recursion_bounds"]


def band_block(chol: np.ndarray, rows: slice, cols: slice) -> np.ndarray:
    """Dense ``L[rows, cols]`` of a lower band-stored factor (``chol[d, j] = L[j + d, j]``),
    filled one stored diagonal at a time."""
    out = np.zeros((rows.stop - rows.start, cols.stop - cols.start))
    for d in range(chol.shape[0]):
        j = np.arange(max(cols.start, rows.start - d), min(cols.stop, rows.stop - d))
        out[j + d - rows.start, j - cols.start] = chol[d, j]
    return out


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


def _inverse_factor(chol: np.ndarray, block: slice):
    """``L[block, block]^-1`` (lower triangular, LAPACK trtri) and ``L^-T L^-1`` over the block."""
    inv, info = dtrtri(band_block(chol, block, block), lower=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"triangular inverse failed (info={info})")
    return inv, inv.T @ inv


def inverse_windows(chol: np.ndarray, bounds: np.ndarray):
    """Yield ``(start, Z)`` per block of ``bounds``, last first: ``Z = C^-1[start:stop, start:stop]``
    over the block and the one after it (``stop`` is the end of that next block, or n).

    ``bounds`` are block edges from 0 to n, every block but the last at least the factor's
    bandwidth ``kd`` long (`recursion_bounds`). ``L[k+1, k]`` is then zero but for its
    top-right ``kd x kd`` corner, which keeps each step at one triangular inverse and one
    product of the block.
    """
    if bounds[0] != 0 or bounds[-1] != chol.shape[1]:
        raise ValueError(f"block edges must run from 0 to {chol.shape[1]}, got {bounds[0]} to {bounds[-1]}")
    kd = chol.shape[0] - 1
    blocks = [slice(int(a), int(b)) for a, b in pairwise(bounds)]
    _, z_next = _inverse_factor(chol, blocks[-1])
    yield blocks[-1].start, z_next
    for k in range(len(blocks) - 2, -1, -1):
        here, after = blocks[k], blocks[k + 1]
        c = min(kd, after.stop - after.start)
        inv_kk, z_here = _inverse_factor(chol, here)
        corner = band_block(chol, slice(after.start, after.start + c), slice(here.stop - kd, here.stop))
        z_below = -(z_next[:, :c] @ corner) @ inv_kk[-kd:]
        z_here -= inv_kk[-kd:].T @ (corner.T @ z_below[:c])
        yield here.start, np.block([[z_here, z_below.T], [z_below, z_next]])
        z_next = z_here
