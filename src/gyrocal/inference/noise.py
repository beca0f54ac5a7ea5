"""The noise model of the attitude error, as a banded covariance per maneuver.

Two sources shape the error series: the star tracker's white noise, anisotropic about
its boresight (shared by every channel set, since all are compared with the same
star-tracker sample), and the gyros' angle random walk, which accumulates in the
propagated attitude. Taking first differences in time (the first sample kept) turns
the walk into white noise and the star-tracker noise into an MA(1) process, so the
covariance of the differenced, set-stacked series is block tridiagonal: O(N) to
factor with LAPACK's banded Cholesky. Its three components are linear in
``sigma_cross^2``, ``sigma_about^2`` and ``ARW^2``.
"""

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cholesky_banded
from scipy.linalg.lapack import dtbtrs

from gyrocal.inference.errormodel import Linearization
from gyrocal.model.units import ARCSEC_RAD, DEG_SQRT_H_RAD_SQRT_S

__all__ = [
    "COMPONENTS", "NOISE_LABELS", "NOISE_SCALES", "TAPER_CORRELATION_TIMES", "ManeuverNoise", "NoiseScale", "build",
    "correlation_depth", "difference", "log_sigma_of", "noise_knowledge", "nuisance_design", "scales_in_units",
    "star_tracker_correlation", "stated_scales", "stated_si", "variances", "whiten"
]

COMPONENTS = ("cross", "about", "walk")


@dataclass(frozen=True)
class NoiseScale:
    """One noise scale: its name in the contract's unit, and that unit in SI."""

    key: str
    si_per_unit: float


NOISE_SCALES = (NoiseScale("sigma_cross_arcsec", ARCSEC_RAD), NoiseScale("sigma_about_arcsec", ARCSEC_RAD),
                NoiseScale("arw_deg_sqrt_h", DEG_SQRT_H_RAD_SQRT_S))
"""The three sampled scales, in the order of ``log_sigma``: star tracker across and about its
boresight (rad), gyro angle random walk (rad/sqrt(s))."""

NOISE_LABELS = [f"noise.{s.key}" for s in NOISE_SCALES]
"""The noise scales' labels in ``posterior_summary.csv`` (beside the channel parameters')."""


def stated_si(stated: dict) -> np.ndarray:
    """The three scales (SI) of noise given in the contract's units."""
    return np.array([stated[s.key] * s.si_per_unit for s in NOISE_SCALES])


def log_sigma_of(stated: dict) -> np.ndarray:
    """``log_sigma`` of noise given in the contract's units."""
    return np.log(stated_si(stated))


def scales_in_units(log_sigma) -> np.ndarray:
    """The noise scales of ``log_sigma`` (last axis) in the contract's units."""
    return np.exp(np.asarray(log_sigma, dtype=float)) / np.array([s.si_per_unit for s in NOISE_SCALES])


def stated_scales(log_sigma) -> dict:
    """``{key: value}`` of one ``log_sigma`` in the contract's units, for JSON files."""
    return {s.key: float(v) for s, v in zip(NOISE_SCALES, scales_in_units(log_sigma))}


def noise_knowledge(info: dict, defaults: dict) -> dict:
    """The star-tracker and gyro noise knowledge: campaign.yaml (as recorded in
    ``input.json``, or a plan's scenario) first, then the config's ``noise`` section."""
    keys = ("sigma_cross_arcsec", "sigma_about_arcsec", "boresight_body", "arw_deg_sqrt_h")
    stated = {**info["star_tracker"], **info["gyro"]}
    return {k: stated.get(k, defaults[k]) for k in keys}


def variances(log_sigma) -> dict:
    """Noise variances from ``log [sigma_cross_rad, sigma_about_rad, arw_rad_sqrt_s]``."""
    s = np.exp(2.0 * np.asarray(log_sigma, dtype=float))
    return {"cross": s[0], "about": s[1], "walk": s[2]}


def _banded_lower(diag_blocks, lower_blocks, depth=1):
    """LAPACK lower band storage of a symmetric block-banded matrix.

    ``lower_blocks[d - 1]`` holds the blocks d steps below the diagonal (d <= depth).
    """
    n_blocks, m, _ = diag_blocks.shape
    kd = (depth + 1) * m - 1
    ab = np.zeros((kd + 1, n_blocks * m))
    a, b = np.tril_indices(m)
    starts = m * np.arange(n_blocks)
    rows = (starts[:, None] + a[None]).ravel()
    cols = (starts[:, None] + b[None]).ravel()
    ab[rows - cols, cols] = diag_blocks[:, a, b].ravel()
    a, b = np.indices((m, m)).reshape(2, -1)
    for d in range(1, min(depth, n_blocks - 1) + 1):
        rows = (starts[d:, None] + a[None]).ravel()
        cols = (starts[:-d, None] + b[None]).ravel()
        ab[rows - cols, cols] = lower_blocks[d - 1][:, a, b].ravel()
    return ab


def difference(series: np.ndarray) -> np.ndarray:
    """First differences along time with the first sample kept (the transform above)."""
    return np.concatenate([series[:1], np.diff(series, axis=0)])


@dataclass
class ManeuverNoise:
    """Banded covariance components and the differenced right-hand sides of one maneuver."""

    maneuver: str
    components: dict
    """name -> (kd+1, n) lower band storage, per unit variance; the gyro's ``walk`` as its main
    diagonal alone, (n,), where it has nothing off it (`build`): a third of the storage."""
    rhs: np.ndarray
    """(n, P + G + 1): differenced design, nuisance design and data, flattened; column-major,
    as LAPACK's banded solve takes it (a row-major copy costs it half as much again)."""
    n_params: int
    n_nuisance: int

    @property
    def n(self) -> int:
        return self.rhs.shape[0]

    def covariance(self, variances: dict) -> np.ndarray:
        """The banded covariance: ``sum(variances[k] * components[k])``, to the bit (the walk's
        zeros off the diagonal added nothing: no entry of the first two's sum is -0.0)."""
        out = sum(variances[k] * self.components[k] for k in COMPONENTS[:2])
        walk = self.components["walk"]
        if walk.ndim == 1:
            out[0] += variances["walk"] * walk
            return out
        return out + variances["walk"] * walk

    def factor(self, variances: dict) -> np.ndarray:
        return cholesky_banded(self.covariance(variances), lower=True)

    def gram(self, variances: dict):
        """``rhs^T C^-1 rhs`` and ``log det C``."""
        chol = self.factor(variances)
        white = self.whiten(chol, self.rhs)
        return white.T @ white, 2.0 * np.sum(np.log(chol[0]))

    def whiten(self, chol: np.ndarray, x: np.ndarray) -> np.ndarray:
        """``L^-1 x`` for the banded Cholesky factor ``L`` (`whiten`)."""
        return whiten(chol, x)


def whiten(chol: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``L^-1 x`` for a banded Cholesky factor ``L`` (`ManeuverNoise.factor`), column by column."""
    x2 = x.reshape(len(x), -1)
    out, info = dtbtrs(chol, x2, uplo="L")
    if info != 0:
        raise np.linalg.LinAlgError(f"banded triangular solve failed (info={info})")
    return out.reshape(x.shape)


def nuisance_design(lin: Linearization) -> np.ndarray:
    """(M, S, 3, 3 + n_channels): initial attitude error ``chi0`` (shared) and biases."""
    m, n_sets = lin.z.shape[:2]
    chi0 = np.zeros((m, n_sets, 3, 3))
    chi0[:, :, np.arange(3), np.arange(3)] = 1.0
    return np.concatenate([chi0, lin.bias_design], axis=3)


TAPER_CORRELATION_TIMES = 6.0
"""Correlated star-tracker noise: the AR(1) correlation is tapered (Bartlett) to zero at
this many correlation times, which keeps the covariance banded and positive definite."""


def star_tracker_correlation(st_time, lag, correlation_time_s):
    """Correlation of the star-tracker noise between samples ``lag`` apart (tapered AR(1))."""
    if lag == 0:
        return np.ones(len(st_time))
    if correlation_time_s <= 0:
        return np.zeros(len(st_time) - lag)
    gap = st_time[lag:] - st_time[:-lag]
    cutoff = TAPER_CORRELATION_TIMES * correlation_time_s
    return np.exp(-gap / correlation_time_s) * np.clip(1 - gap / cutoff, 0, None)


def correlation_depth(st_time, correlation_time_s) -> int:
    """How many samples apart the tapered correlation reaches."""
    if correlation_time_s <= 0:
        return 0
    step = np.median(np.diff(st_time))
    return int(np.ceil(TAPER_CORRELATION_TIMES * correlation_time_s / step))


def build(lin: Linearization, boresight_body, correlation_time_s: float = 0.0) -> ManeuverNoise:
    """Covariance components and differenced right-hand sides of a linearised maneuver.

    With ``correlation_time_s`` > 0 the star-tracker noise is first-order Gauss-Markov
    (a filtered attitude) instead of white; the band widens to cover its reach.
    """
    m_samples, n_sets = lin.z.shape[:2]
    block = 3 * n_sets
    b = np.asarray(boresight_body, dtype=float)
    b = b / np.linalg.norm(b)
    about_body = np.outer(b, b)
    ones = np.ones((n_sets, n_sets))
    R = lin.st_matrix
    st_time = np.cumsum(lin.st_dt)
    reach = min(correlation_depth(st_time, correlation_time_s), max(m_samples - 1, 0))
    depth = reach + 1
    diag, lower = {}, {}
    for name, body_cov in (("cross", np.eye(3) - about_body), ("about", about_body)):
        rs = np.einsum("jab,bc->jac", R, body_cov)

        def cov(lag, rs=rs):
            """Undifferenced covariance blocks between samples j + lag and j (zero-padded)."""
            if lag > reach or lag >= m_samples:
                return np.zeros((max(m_samples - lag, 0), block, block))
            c = star_tracker_correlation(st_time, lag, correlation_time_s)
            u = c[:, None, None] * np.einsum("jab,jcb->jac", rs[lag:], R[:m_samples - lag])
            return np.einsum("st,jab->jsatb", ones, u).reshape(m_samples - lag, block, block)

        # Cov(Z_{k+lag}, Z_k) for lag = 0 .. depth + 1; D_j = Z_j - Z_{j-1}, D_0 = Z_0, so
        # Cov(D_{k+d}, D_k) = K(d, k) - K(d+1, k-1) - K(d-1, k) + K(d, k-1), K(., -1) = 0
        blocks = [cov(lag) for lag in range(depth + 2)]

        def get(lag, idx, blocks=blocks):
            out = np.zeros((len(idx), block, block))
            ok = (idx >= 0) & (idx < len(blocks[lag]))
            out[ok] = blocks[lag][idx[ok]]
            return out

        j = np.arange(m_samples)
        up = get(1, j - 1)
        d0 = get(0, j) - up - np.transpose(up, (0, 2, 1)) + get(0, j - 1)
        lowers = []
        for d in range(1, depth + 1):
            k = np.arange(m_samples - d)
            lowers.append(get(d, k) - get(d + 1, k - 1) - get(d - 1, k) + get(d, k - 1))
        diag[name], lower[name] = d0, lowers
    walk = lin.random_walk().transpose(0, 1, 3, 2, 4).reshape(m_samples, block, block)
    components = {k: _banded_lower(diag[k], lower[k], depth) for k in COMPONENTS[:2]}
    on_diagonal = np.einsum("jaa->ja", walk)
    if np.count_nonzero(walk) == np.count_nonzero(on_diagonal):  # each set's walk is isotropic: dt I
        components["walk"] = on_diagonal.ravel()
    else:
        components["walk"] = _banded_lower(walk, [np.zeros((max(m_samples - d, 0), block, block))
                                                  for d in range(1, depth + 1)], depth)
    nuis = difference(nuisance_design(lin))
    n = m_samples * block
    rhs = np.asfortranarray(np.concatenate([
        difference(lin.design).reshape(n, -1),
        nuis.reshape(n, -1),
        difference(lin.z).reshape(n, 1),
    ], axis=1))
    return ManeuverNoise(lin.maneuver, components, rhs, lin.design.shape[-1], nuis.shape[-1])
