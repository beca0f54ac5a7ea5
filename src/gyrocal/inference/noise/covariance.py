"""The noise model of the attitude error, as a banded covariance per maneuver.

Two sources shape the error series: the star tracker's white noise, anisotropic about
its boresight (shared by every channel set, since all are compared with the same
star-tracker sample), and the gyros' angle random walk, which accumulates in the
propagated attitude. Taking first differences in time (the first sample kept) turns
the walk into white noise and the star-tracker noise into an MA(1) process, so the
covariance of the differenced, set-stacked series is block tridiagonal: O(N) to
factor with LAPACK's banded Cholesky. Its three components are linear in
``sigma_cross^2``, ``sigma_about^2`` and ``ARW^2``. Star-tracker noise with a Gauss-Markov
part is filtered instead (`markov`): two samples deep, two more components. A timing jitter of
the reference (sd ``sigma_t``, `st_jitter`) adds one more, linear in ``sigma_t^2``: the
reference attitude taken ``dt`` off its time tag errs by ``omega dt``, a white error of covariance
``sigma_t^2 omega omega^T`` at each sample, along the rotation axis (rank one), as banded as the rest,
differenced or filtered alike (white, it has no Gauss-Markov counterpart).

The noise scales (``log_sigma``) are laid out as `noise_scales` gives them: the three white ones,
then with correlated noise the Gauss-Markov share and tau, then with the jitter ``sigma_t``. Each
`NoiseScale` says how it enters the covariance; the layout's length (3 to 6) tells which it is.
"""

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cholesky_banded
from scipy.linalg.lapack import dtbtrs
from scipy.special import expit, logit

from gyrocal.inference.errormodel import Linearization
from gyrocal.inference.noise import markov
from gyrocal.io.campaign_yaml import GM_CLOCK_AUTO, GM_CLOCK_KEY, SIGMA_IS_KEY
from gyrocal.model.units import ARCSEC_RAD, DEG_SQRT_H_RAD_SQRT_S

__all__ = [
    "COMPONENTS",
    "CORRELATED_SCALES",
    "GM_FRACTION_SCALE",
    "GM_PRIOR_ANGLE_RAD",
    "GM_TAU_SCALE",
    "JITTER_FLOOR_S",
    "JITTER_SCALE",
    "NOISE_LABELS",
    "NOISE_SCALES",
    "ManeuverNoise",
    "NoiseScale",
    "absolute_of",
    "build",
    "correlation_time_of",
    "difference",
    "filtered",
    "gm_tau_prior_s",
    "jitter_shapes",
    "jitter_stated_ms",
    "log_sigma_of",
    "noise_knowledge",
    "noise_labels",
    "noise_scales",
    "nuisance_design",
    "position",
    "ratio_position",
    "ratios_of",
    "scales_in_units",
    "scales_of",
    "stated_scales",
    "stated_si",
    "transformed",
    "unit_variances",
    "untransformed",
    "variances",
    "whiten"
]

COMPONENTS = ("cross", "about", "walk")


@dataclass(frozen=True)
class NoiseScale:
    """One noise scale: its name in the contract's unit, and that unit in SI; sampled as its log,
    or as its logit where it is a fraction."""

    key: str
    si_per_unit: float
    logit: bool = False
    prior_center: float | None = None
    """The prior's median in the unit of ``key`` where no data sheet states it (None: the stated value)."""
    prior_log_sd: float | None = None
    """The log-normal prior's sd where it is the scale's own (None: the config's ``noise_log_sd``)."""
    relative: bool = True
    """Whether the covariance takes it as its ratio to ``sigma_cross`` (an sd that scales a component:
    the white scales, the jitter's), or as itself (the Gauss-Markov share and tau, which shape it at
    any level): `ratios_of`."""


NOISE_SCALES = (NoiseScale("sigma_cross_arcsec", ARCSEC_RAD), NoiseScale("sigma_about_arcsec", ARCSEC_RAD),
                NoiseScale("arw_deg_sqrt_h", DEG_SQRT_H_RAD_SQRT_S))
"""The three sampled scales, in the order of ``log_sigma``: star tracker across and about its
boresight (rad), gyro angle random walk (rad/sqrt(s))."""

GM_FRACTION_SCALE = NoiseScale("st_gm_fraction", 1.0, logit=True, prior_center=0.5, prior_log_sd=2.0, relative=False)
"""With correlated star-tracker noise (`markov`), the share of the star tracker's variance that is
Gauss-Markov (the same share across and about the boresight, so ``sigma_cross`` and ``sigma_about``
stay its total sd, as data sheets state it); its prior logit-normal about one half, sd 2 (12 % to
88 % within one sd)."""

GM_TAU_SCALE = NoiseScale("st_gm_tau_s", 1.0, prior_center=30.0, prior_log_sd=2.0, relative=False)
"""... and its correlation time (s); its prior log-normal about 30 s, sd 2: 4 s to 220 s within one
sd, 0.5 s to 1 600 s within two (with a clock on the angle turned, about `gm_tau_prior_s`)."""

GM_PRIOR_ANGLE_RAD = 1.0
"""With a clock on the angle turned, tau's prior median adds this angle's clock seconds: the error
forgets over 30 s at rest or about a radian turned (a marker set seen by other cameras)."""

CORRELATED_SCALES = NOISE_SCALES + (GM_FRACTION_SCALE, GM_TAU_SCALE)
"""The scales with correlated star-tracker noise: the white three, its share and correlation time."""

JITTER_SCALE = NoiseScale("st_jitter_ms", 1e-3, prior_center=1.0, prior_log_sd=2.0)
"""The reference's timing jitter against the gyros' clock (`st_jitter`), sampled as its log after
the others: the prior's median 1 ms (a clock sync over USB or a network), its sd a
factor e^2, 0.14 to 7 ms within one sd and 18 us to 55 ms within two; a campaign.yaml's
``star_tracker: st_jitter_ms`` moves the median."""

JITTER_FLOOR_S = 1e-6
"""The REML keeps ``sigma_t`` above this: 1 us, 0.2 arcsec at 1 rad/s, where the profile is flat."""

NOISE_LABELS = [f"noise.{s.key}" for s in NOISE_SCALES]
"""The noise scales' labels in ``posterior_summary.csv`` (beside the channel parameters')."""


def noise_scales(correlated: bool, jitter: bool = False) -> tuple:
    """The scales a model samples, in the order of ``log_sigma``: the three white ones, then with
    correlated star-tracker noise its share and tau, then with the reference's timing jitter its sd
    (3, 4, 5 or 6): the one place the layout is declared."""
    return (CORRELATED_SCALES if correlated else NOISE_SCALES) + ((JITTER_SCALE,) if jitter else ())


_LAYOUTS = {len(noise_scales(c, j)): noise_scales(c, j) for c in (False, True) for j in (False, True)}


def noise_labels(correlated: bool, jitter: bool = False) -> list:
    """`NOISE_LABELS` of a model: with correlated noise or jitter, their scales too."""
    return [f"noise.{s.key}" for s in noise_scales(correlated, jitter)]


def scales_of(log_sigma) -> tuple:
    """The `noise_scales` that ``log_sigma`` (last axis) holds, told by its length."""
    return _LAYOUTS[np.shape(log_sigma)[-1]]


def position(log_sigma, scale: NoiseScale) -> int | None:
    """Where ``scale`` sits on the last axis of ``log_sigma``; None where its model has no such scale."""
    scales = scales_of(log_sigma)
    return scales.index(scale) if scale in scales else None


def ratio_position(ratios, scale: NoiseScale) -> int | None:
    """Where ``scale`` sits on the last axis of `ratios_of`'s ratios (``sigma_cross`` has none)."""
    scales = _LAYOUTS[np.shape(ratios)[-1] + 1]
    return scales.index(scale) - 1 if scale in scales[1:] else None


def correlation_time_of(ratios) -> float:
    """The Gauss-Markov correlation time (s) of one row of `ratios_of`'s ratios; 0 where the noise is white."""
    k = ratio_position(ratios, GM_TAU_SCALE)
    return 0.0 if k is None else float(np.exp(ratios[k]))


def gm_tau_prior_s(stated: dict) -> float:
    """Tau's prior median (s of the part's clock): `GM_TAU_SCALE`'s, plus with a clock on the angle turned
    (campaign.yaml's ``star_tracker``: `GM_CLOCK_KEY`) that clock's seconds over `GM_PRIOR_ANGLE_RAD`."""
    return GM_TAU_SCALE.prior_center + float(stated.get(GM_CLOCK_KEY, 0.0)) * GM_PRIOR_ANGLE_RAD


def _prior_center(scale: NoiseScale, stated: dict) -> float:
    return gm_tau_prior_s(stated) if scale is GM_TAU_SCALE else scale.prior_center


def jitter_stated_ms(stated: dict) -> float:
    """The stated timing jitter (ms): the campaign's ``st_jitter_ms``, or `JITTER_SCALE`'s prior median."""
    return float(stated.get(JITTER_SCALE.key, JITTER_SCALE.prior_center))


def stated_si(stated: dict) -> np.ndarray:
    """The three scales (SI) of noise given in the contract's units."""
    return np.array([stated[s.key] * s.si_per_unit for s in NOISE_SCALES])


def log_sigma_of(stated: dict, jitter: bool = False, correlated: bool = False) -> np.ndarray:
    """``log_sigma`` (`noise_scales`) of noise given in the contract's units: each scale as stated, or
    its prior's median where it has one and nothing states it (the jitter's: `jitter_stated_ms`; tau's:
    `gm_tau_prior_s`); a fraction as its logit."""
    scales = noise_scales(correlated, jitter)
    si = [(stated[s.key] if s.prior_center is None else float(stated.get(s.key, _prior_center(s, stated))))
          * s.si_per_unit for s in scales]
    return np.array([logit(v) if s.logit else np.log(v) for s, v in zip(scales, si)])


def scales_in_units(log_sigma) -> np.ndarray:
    """The noise scales of ``log_sigma`` (last axis) in the contract's units (a fraction from its logit)."""
    log_sigma = np.asarray(log_sigma, dtype=float)
    scales = scales_of(log_sigma)
    fraction = np.array([s.logit for s in scales])
    values = np.where(fraction, expit(log_sigma), np.exp(np.where(fraction, 0.0, log_sigma)))
    return values / np.array([s.si_per_unit for s in scales])


def stated_scales(log_sigma) -> dict:
    """``{key: value}`` of one ``log_sigma`` in the contract's units, for JSON files."""
    return {s.key: float(v) for s, v in zip(scales_of(log_sigma), scales_in_units(log_sigma))}


def noise_knowledge(info: dict, defaults: dict) -> dict:
    """The star-tracker and gyro noise knowledge: campaign.yaml (as recorded in
    ``input.json``, or a plan's scenario) first, then the config's ``noise`` section."""
    keys = ("sigma_cross_arcsec", "sigma_about_arcsec", "boresight_body", "arw_deg_sqrt_h")
    stated = {**info["star_tracker"], **info["gyro"]}
    out = {k: stated.get(k, defaults[k]) for k in keys}
    for key in (JITTER_SCALE.key, GM_CLOCK_KEY, SIGMA_IS_KEY):  # only where stated: by default the three scales
        value = stated.get(key, defaults.get(key))
        if value is not None and value != GM_CLOCK_AUTO:  # a clock to choose: the maneuvers carry the one chosen
            out[key] = value
    return out


def variances(log_sigma) -> dict:
    """Noise variances from ``log_sigma`` (`noise_scales`): ``log [sigma_cross_rad, sigma_about_rad,
    arw_rad_sqrt_s]``; with correlated noise the star tracker's variance splits into its white and
    Gauss-Markov shares (tau is not a variance); with the timing jitter, ``sigma_t^2`` (s^2)."""
    log_sigma = np.asarray(log_sigma, dtype=float)
    s = np.exp(2.0 * log_sigma[:3])
    out = {"cross": s[0], "about": s[1], "walk": s[2]}
    share = position(log_sigma, GM_FRACTION_SCALE)
    if share is not None:
        white, gm = expit(-log_sigma[share]), expit(log_sigma[share])
        out = {"cross": s[0] * white, "about": s[1] * white, "walk": s[2], "gm_cross": s[0] * gm, "gm_about": s[1] * gm}
    jitter = position(log_sigma, JITTER_SCALE)
    if jitter is not None:
        out["jitter"] = float(np.exp(2.0 * log_sigma[jitter]))
    return out


def _relative(scales) -> np.ndarray:
    return np.array([s.relative for s in scales])


def ratios_of(log_sigma) -> np.ndarray:
    """What the covariance's shape depends on (last axis): each scale after ``sigma_cross``, as its log
    ratio to it where it is `NoiseScale.relative` (``sigma_about``, the ARW, the jitter's ``sigma_t``),
    else as itself (``logit st_gm_fraction``, ``log tau_s``); ``sigma_cross^2`` enters in closed form."""
    log_sigma = np.asarray(log_sigma, dtype=float)
    relative = _relative(scales_of(log_sigma)[1:])
    return np.where(relative, log_sigma[..., 1:] - log_sigma[..., :1], log_sigma[..., 1:])


def unit_variances(ratios) -> dict:
    """`variances` at unit ``sigma_cross`` from `ratios_of`'s ratios."""
    ratios = np.asarray(ratios, dtype=float)
    return variances(np.concatenate([[0.0], ratios]))


def absolute_of(log_cross, ratios) -> np.ndarray:
    """`ratios_of`'s inverse: ``log_sigma`` from ``log sigma_cross`` and the ratios."""
    ratios = np.asarray(ratios, dtype=float)
    relative = _relative(_LAYOUTS[len(ratios) + 1][1:])
    return np.concatenate([[log_cross], np.where(relative, log_cross + ratios, ratios)])


def _banded_lower(diag_blocks, lower_blocks, depth=1):
    """LAPACK lower band storage of a symmetric block-banded matrix.

    ``lower_blocks[d - 1]`` holds the blocks d steps below the diagonal (d <= depth). Band row k
    of column ``j m + b`` is entry ``((b + k) mod m, b)`` of the block ``(b + k) // m`` steps below
    sample j's diagonal: one strided copy per (k, b), no scatter.
    """
    n_blocks, m, _ = diag_blocks.shape
    kd = (depth + 1) * m - 1
    ab = np.zeros((kd + 1, n_blocks * m))
    for k in range(kd + 1):
        for b in range(m):
            lag, a = divmod(b + k, m)
            if lag == 0:
                ab[k, b::m] = diag_blocks[:, a, b]
            elif lag <= min(depth, n_blocks - 1):
                ab[k, b:(n_blocks - lag) * m:m] = lower_blocks[lag - 1][:, a, b]
    return ab


def difference(series: np.ndarray) -> np.ndarray:
    """First differences along time with the first sample kept (the transform above)."""
    return np.concatenate([series[:1], np.diff(series, axis=0)])


def transformed(series: np.ndarray, filt) -> np.ndarray:
    """A series (M, ...) as the noise's right-hand sides hold it: first-differenced (``filt`` None),
    or through a Gauss-Markov `markov.Filter`."""
    return difference(series) if filt is None else filt.apply(series)


def untransformed(series: np.ndarray, filt) -> np.ndarray:
    """`transformed`'s inverse along the first axis: cumulative sums, or the filter's inverse."""
    return np.cumsum(series, axis=0) if filt is None else filt.invert(series)


@dataclass
class ManeuverNoise:
    """Banded covariance components and the transformed (differenced, or Gauss-Markov filtered)
    right-hand sides of one maneuver."""

    maneuver: str
    components: dict
    """name -> (kd+1, n) lower band storage, per unit variance; the gyro's ``walk`` as its main
    diagonal alone, (n,), where it has nothing off it (`build`): a third of the storage."""
    rhs: np.ndarray
    """(n, P + G + 1): differenced design, nuisance design and data, flattened; column-major,
    as LAPACK's banded solve takes it (a row-major copy costs it half as much again)."""
    n_params: int
    n_nuisance: int
    filter: markov.Filter | None = None
    """The Gauss-Markov filter of correlated noise; None: first differences."""

    @property
    def n(self) -> int:
        return self.rhs.shape[0]

    def covariance(self, variances: dict) -> np.ndarray:
        """The banded covariance: ``sum(variances[k] * components[k])``, to the bit (the walk's
        zeros off the diagonal added nothing: no entry of the first two's sum is -0.0)."""
        out = sum(variances[k] * c for k, c in self.components.items() if k != "walk")
        walk = self.components["walk"]
        if walk.ndim == 1:
            out[0] += variances["walk"] * walk
            return out
        return out + variances["walk"] * walk

    def transform(self, series: np.ndarray) -> np.ndarray:
        """The series (M, ...) as ``rhs`` holds it: first-differenced, or Gauss-Markov filtered."""
        return transformed(series, self.filter)

    def untransform(self, transformed: np.ndarray) -> np.ndarray:
        """`transform`'s inverse along the first axis."""
        return untransformed(transformed, self.filter)

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


def _body_shapes(boresight_body) -> dict:
    """The star tracker's noise shapes across and about its boresight (body axes)."""
    b = np.asarray(boresight_body, dtype=float)
    b = b / np.linalg.norm(b)
    return {"cross": np.eye(3) - np.outer(b, b), "about": np.outer(b, b)}


def jitter_shapes(lin: Linearization) -> np.ndarray:
    """(M, 3, 3) the timing jitter's covariance per unit ``sigma_t^2`` at each reference sample, body axes:
    ``omega omega^T`` of the body rate there (`Linearization.st_body_rate`)."""
    if lin.st_body_rate is None:
        raise ValueError(f"maneuver {lin.maneuver}: the timing jitter needs the body rate at the reference samples")
    return np.einsum("ja,jb->jab", lin.st_body_rate, lin.st_body_rate)


def filtered(maneuver: str, z, design, nuisance, st_matrix, walk, st_dt, walk_lag1, boresight_body,
             correlation_time_s: float, jitter=None) -> ManeuverNoise:
    """A `ManeuverNoise` of star-tracker noise with a Gauss-Markov part (`markov`): its exact filter,
    two samples deep, and two more components; from the arrays of one series (`build`, or maneuvers
    chained by `segments`): ``z`` (M, S, 3), ``design`` and ``nuisance`` (M, S, 3, .), ``walk`` (M, S, S, 3, 3).
    ``jitter`` (M, 3, 3, `jitter_shapes`): the timing jitter's component too, white, filtered as the
    tracker's white noise is; None: none."""
    m_samples, n_sets = z.shape[:2]
    n = m_samples * 3 * n_sets
    white = None if jitter is None else {"jitter": jitter}
    blocks, filt = markov.covariance_blocks(st_matrix, _body_shapes(boresight_body), walk, st_dt, correlation_time_s,
                                            n_sets, walk_lag1, white)
    components = {k: _banded_lower(v[0], [v[1][1:], v[2][2:]], 2) for k, v in blocks.items()}
    rhs = np.asfortranarray(np.concatenate([filt.apply(design).reshape(n, -1), filt.apply(nuisance).reshape(n, -1),
                                            filt.apply(z).reshape(n, 1)], axis=1))
    return ManeuverNoise(maneuver, components, rhs, design.shape[-1], nuisance.shape[-1], filt)


def build(lin: Linearization, boresight_body, correlation_time_s: float = 0.0, jitter: bool = False) -> ManeuverNoise:
    """Covariance components and transformed right-hand sides of a linearised maneuver.

    White star-tracker noise: first differences, the covariance one sample deep. With
    ``correlation_time_s`` > 0 the star-tracker noise has a Gauss-Markov part too
    (`filtered`). ``jitter``: one more component, the reference's timing jitter, ``omega omega^T``
    per unit ``sigma_t^2`` at each sample (`jitter_shapes`), white like the tracker's, with either.
    """
    m_samples, n_sets = lin.z.shape[:2]
    block = 3 * n_sets
    nuis = nuisance_design(lin)
    n = m_samples * block
    if correlation_time_s > 0:
        return filtered(lin.maneuver, lin.z, lin.design, nuis, lin.st_matrix, lin.random_walk(), lin.gm_steps,
                        lin.walk_lag1_or_none(), boresight_body, correlation_time_s,
                        jitter_shapes(lin) if jitter else None)
    shapes = _body_shapes(boresight_body)
    if jitter:
        shapes["jitter"] = jitter_shapes(lin)
    R = lin.st_matrix
    ones = np.ones((n_sets, n_sets))
    diag, lower = {}, {}
    for name, body_cov in shapes.items():
        per_sample = "jbc" if body_cov.ndim == 3 else "bc"
        u = np.einsum("jab,jcb->jac", np.einsum(f"jab,{per_sample}->jac", R, body_cov), R)
        u = markov.over_sets(ones, u)
        # D_j = Z_j - Z_(j-1), D_0 = Z_0: Var D_j = U_j + U_(j-1), Cov(D_(k+1), D_k) = -U_k
        d0 = u.copy()
        d0[1:] += u[:-1]
        diag[name], lower[name] = d0, [-u[:-1]]
    walk = lin.random_walk().transpose(0, 1, 3, 2, 4).reshape(m_samples, block, block)
    components = {k: _banded_lower(diag[k], lower[k]) for k in shapes}
    on_diagonal = np.einsum("jaa->ja", walk)
    shared = lin.walk_lag1_or_none()
    if shared is None and np.count_nonzero(walk) == np.count_nonzero(on_diagonal):  # isotropic: dt I
        components["walk"] = on_diagonal.ravel()
    else:  # samples inside gyro intervals: consecutive steps share the walk of the interval between
        lag1 = np.zeros((max(m_samples - 1, 0), block, block))
        if shared is not None:
            lag1 += shared[1:, None, None] * np.eye(block)
        components["walk"] = _banded_lower(walk, [lag1])
    rhs = np.asfortranarray(np.concatenate([
        difference(lin.design).reshape(n, -1),
        difference(nuis).reshape(n, -1),
        difference(lin.z).reshape(n, 1),
    ], axis=1))
    return ManeuverNoise(lin.maneuver, components, rhs, lin.design.shape[-1], nuis.shape[-1])
