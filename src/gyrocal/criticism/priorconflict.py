"""Prior-data conflict: where the likelihood sits in each parameter's prior.

The WLS point estimate is the likelihood's alone (its fit has no prior term) and its Jacobian
covariance is the inverse Fisher information, so per parameter the data say ``theta_lik +-
lik_sd``. Under the prior, that estimate is distributed ``N(prior_mean, prior_sd^2 + lik_sd^2)``
(the prior predictive of a linear Gaussian model), so

    z = (theta_lik - prior_mean) / sqrt(prior_sd^2 + lik_sd^2)

says how far in the prior's tail the data put it, and ``(mean - theta_lik) / lik_sd`` how far the
prior then pulls the posterior off what the data say. Beyond `Z_MAX` the two disagree: a prior
too narrow for this gyro (a MEMS triad under a DTG's prior), or a parameter far out of its
expected range. The posterior is then not what the data support, and its interval may miss the
truth: the verdict refuses a GO where a core term conflicts, or where a conflict pulls the
posterior by more than `SHIFT_MAX` of the likelihood's sd.

The effects beyond the channel model have Student-t priors (`gyrocal.model.priorfamily`): a
conflict there is still reported (``z`` counts the prior's scales, whatever its family; the tail
probability is the family's), but the heavy tail lets the data decide, the posterior stays near
the likelihood, and the conflict warns instead of blocking.
"""

import numpy as np
import pandas as pd

from gyrocal.finding import Finding, Status
from gyrocal.model import priorfamily
from gyrocal.model.spec import CONFIG_PRIOR_KEYS

__all__ = ["CHECK", "SHIFT_MAX", "Z_MAX", "conflict_check", "conflict_table", "widen_key"]

CHECK = "no prior-data conflict"

Z_MAX = 3.0
"""|z| beyond which the likelihood sits in the prior's tail (two-sided tail probability 0.0027)."""

SHIFT_MAX = 1.0
"""A conflicted parameter whose posterior mean the prior moves by more than this many of the
likelihood's sd blocks a GO, core or not: its prior, not the data, decides the answer (and the
core terms correlated with it)."""


def widen_key(p) -> str:
    """The key under the config's ``priors:`` that sets parameter ``p``'s prior sd (a
    `gyrocal.model.spec.ParameterSpec`): ``sf_sd_ppm``, ``mis_sd_arcsec``, else
    ``sd.<effect>.<parameter>`` (``priors: {sd: {<effect>.<parameter>: value}}``)."""
    for key, (effects, field) in CONFIG_PRIOR_KEYS.items():
        if p.effect in effects and field == "prior_sd":
            return key
    return f"sd.{p.effect}.{p.name}"


def _setting(key: str, value: float) -> str:
    """The config's ``priors:`` entry that sets ``key`` (`widen_key`) to ``value``."""
    if key.startswith("sd."):
        return f"priors: {{sd: {{{key[3:]}: {value:g}}}}}"
    return f"priors: {{{key}: {value:g}}}"


def conflict_table(spec, theta_si, cov_si, calibration: pd.DataFrame) -> pd.DataFrame:
    """Per informed parameter of ``spec`` (with the priors the posterior used): the likelihood's
    estimate and sd (``theta_si``, ``cov_si``: the WLS's, SI), the prior, the posterior mean of
    ``calibration`` (its units), ``z``, the prior-predictive two-sided tail probability ``tail_p``,
    the posterior's ``shift_lik_sd`` off the likelihood, and ``conflict`` (|z| > `Z_MAX`).
    Parameter units throughout."""
    posterior = calibration.set_index(calibration["channel"] + "." + calibration["parameter"])["mean"]
    lik = spec.to_unit(np.asarray(theta_si, dtype=float))
    lik_sd = np.sqrt(np.diag(np.asarray(cov_si, dtype=float))) / spec.si_per_unit
    rows = []
    for i, p in enumerate(spec.parameters):
        if p.prior_only or p.label not in posterior.index or not np.isfinite(lik_sd[i]):
            continue
        z = (lik[i] - p.prior_mean) / np.hypot(p.prior_sd, lik_sd[i])
        rows.append({"label": p.label, "unit": p.unit, "core": p.core, "prior_mean": p.prior_mean,
                     "prior_sd": p.prior_sd, "lik": lik[i], "lik_sd": lik_sd[i], "mean": float(posterior[p.label]),
                     "prior_dof": p.prior_dof, "z": z, "tail_p": float(priorfamily.tail_probability(z, p.prior_dof)),
                     "shift_lik_sd": (float(posterior[p.label]) - lik[i]) / lik_sd[i], "conflict": abs(z) > Z_MAX,
                     "key": widen_key(p)})
    return pd.DataFrame(rows, columns=["label", "unit", "core", "prior_mean", "prior_sd", "prior_dof", "lik", "lik_sd",
                                       "mean", "z", "tail_p", "shift_lik_sd", "conflict", "key"])


def _family(dof) -> str:
    """The prior's family in words, after its mean and scale: nothing where normal."""
    return "" if not np.isfinite(dof) else f" (Student-t, {dof:g} degrees of freedom)"


def _suggested_sd(row) -> float:
    """A prior sd that puts the likelihood within 1 sd of the prior's mean, on two figures."""
    wide = max(abs(row.lik - row.prior_mean) + 2.0 * row.lik_sd, 2.0 * row.prior_sd)
    return float(f"{wide:.2g}")


def conflict_check(table: pd.DataFrame) -> Finding:
    """The verdict's finding of `conflict_table`: it passes without a conflict, warns where a
    conflicted parameter is neither core nor pulled by its prior beyond `SHIFT_MAX`, and refuses
    (NO-GO) otherwise. It says where each likelihood sits in its prior's tail and which config
    key widens that prior."""
    conflicted = table[table["conflict"]]
    if conflicted.empty:
        figure = float(table["z"].abs().max()) if len(table) else None
        return Finding(CHECK, Status.PASS, f"every parameter's estimate lies within {Z_MAX:g} sd of its prior "
                       "(prior predictive)", figure=figure, threshold=Z_MAX, unit="sd")
    blocking = conflicted[conflicted["core"] | (conflicted["shift_lik_sd"].abs() > SHIFT_MAX)]
    parts = [f"{r.label}: the data say {r.lik:.4g} +- {r.lik_sd:.2g} {r.unit}, {abs(r.z):.1f} sd into the tail of "
             f"its prior {r.prior_mean:g} +- {r.prior_sd:g}{_family(r.prior_dof)} (tail probability {r.tail_p:.1e}); "
             f"the posterior mean "
             f"{r.mean:.4g} is pulled {abs(r.shift_lik_sd):.1f} of the data's sd toward the prior"
             for r in conflicted.itertuples()]
    worst = conflicted.loc[conflicted["z"].abs().idxmax()]
    widest = conflicted.assign(suggested=[_suggested_sd(r) for r in conflicted.itertuples()]).groupby(
        "key", sort=False)["suggested"].max()
    action = "widen the prior in the config and rerun: " + "; ".join(_setting(k, v) for k, v in widest.items())
    status = Status.REFUSE if len(blocking) else Status.WARN
    why = "prior-data conflict: " + "; ".join(parts) + (
        "" if len(blocking) else f" (not core, and moved by under {SHIFT_MAX:g} of the data's sd)")
    return Finding(CHECK, status, why, figure=float(abs(worst["z"])), threshold=Z_MAX, unit="sd",
                   action=action, where=", ".join(conflicted["label"]))
