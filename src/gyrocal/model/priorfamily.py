"""The prior's family, declared once on each `gyrocal.model.effects.Parameter` (``prior_dof``):
normal (``inf``), or Student-t with ``prior_dof`` degrees of freedom at scale ``prior_sd``. The
effects beyond the channel model (bias drift, nonlinearity, latency, g-sensitivity, gravity
offset) take `EFFECT_PRIOR_DOF`: a prior that says how large the effect usually is, and yields to
data that say it is larger (a 2 deg/h/h ramp under a scale of 0.5 is not pulled to half). The
log-prior, the sampler's proposal, the prior-data conflict and the plan derive from here."""

import numpy as np

__all__ = ["EFFECT_PRIOR_DOF", "heavy", "log_density", "proposal_sd", "tail_probability", "variance_factor"]

EFFECT_PRIOR_DOF = 4.0
"""Degrees of freedom of the effects' Student-t priors: tails heavy enough that data four scales
out are believed (a normal prior would pull them to about half), a finite variance (twice the
scale's square) for the plan."""


def heavy(dof) -> np.ndarray:
    """Mask of the Student-t priors (finite degrees of freedom)."""
    return np.isfinite(np.asarray(dof, dtype=float))


def log_density(z, dof) -> np.ndarray:
    """The log prior of standardised values ``z = (theta - mean) / scale`` (..., P), summed over the
    last axis, up to a constant: ``-z^2 / 2`` where normal, ``-(nu + 1) / 2 log(1 + z^2 / nu)``
    where Student-t."""
    z, dof = np.asarray(z, dtype=float), np.asarray(dof, dtype=float)
    t_mask = heavy(dof)
    if not t_mask.any():
        return -0.5 * np.sum(z**2, axis=-1)
    nu = dof[t_mask]
    return (-0.5 * np.sum(z[..., ~t_mask] ** 2, axis=-1)
            - np.sum(0.5 * (nu + 1.0) * np.log1p(z[..., t_mask] ** 2 / nu), axis=-1))


def proposal_sd(sd, z_hat, dof) -> np.ndarray:
    """The normal prior that stands in for each prior where a method needs a Gaussian one (the
    sampler's conditional proposal, its start, the closed-form leave-one-out): the scale itself where
    normal; where Student-t, the normal whose log density has the t's slope at the data's estimate
    ``z_hat`` (the iteratively reweighted scale ``sd sqrt((nu + z^2) / (nu + 1))``), so that data
    far out in the prior are not pulled back by the stand-in, and at least as wide as the t itself
    (``sd sqrt(nu / (nu - 2))``), where the prior holds the parameter. The exact density
    (`log_density`) decides each step's acceptance."""
    sd, z_hat, dof = (np.asarray(a, dtype=float) for a in (sd, z_hat, dof))
    mask = heavy(dof)
    if not mask.any():
        return sd
    out = sd.copy()
    nu = dof[mask]
    wide = np.minimum(variance_factor(nu), 9.0)  # at most 3 scales where the t has no variance
    out[mask] = sd[mask] * np.sqrt(np.maximum((nu + z_hat[mask] ** 2) / (nu + 1.0), wide))
    return out


def tail_probability(z, dof) -> np.ndarray:
    """Two-sided tail probability of ``|z|`` scales under the prior's family. scipy.stats is imported
    here, not with the module: every step imports the effects, and scipy.stats costs 0.5-1 s of each
    job that needs nothing else of it (validate, preprocess, the point estimate)."""
    from scipy.stats import norm, t

    z, dof = np.abs(np.asarray(z, dtype=float)), np.asarray(dof, dtype=float)
    return np.where(heavy(dof), 2.0 * t.sf(z, np.where(heavy(dof), dof, 1.0)), 2.0 * norm.sf(z))


def variance_factor(dof) -> np.ndarray:
    """The prior's variance over its scale squared: 1 where normal, ``nu / (nu - 2)`` where Student-t
    (infinite at two or fewer degrees of freedom)."""
    dof = np.asarray(dof, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(heavy(dof), np.where(dof > 2, dof / (dof - 2.0), np.inf), 1.0)
