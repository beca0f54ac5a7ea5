"""Which parameters the maneuvers can inform at all; the others are prior-only.

A scale factor of a direction never flown, or a misalignment toward an axis never rotated
about, has no column in the data that is not noise: fitted anyway, it takes up noise and
drags the parameters the data do inform. So is a parameter whose column, once the
nuisance (initial attitude, biases) is integrated out, carries almost no information: a
regressor that is constant, or a copy of the bias. Both are marked prior-only and kept
out of the fit (`errormodel.linearize` gives them no column); their posterior is their
prior, and the verdict names them.
"""

import numpy as np

from gyrocal.inference.likelihood import Stats
from gyrocal.model.spec import ModelSpec

__all__ = ["CORRELATION_MAX", "DETECTION_SD", "INFORMATION_RATIO_MIN", "confounded_pairs", "unflown", "uninformed"]

DETECTION_SD = 5.0
"""A value counts as beyond a physical bound once it exceeds it by this many of its standard errors."""

CORRELATION_MAX = 0.9
"""Two parameters whose predicted posterior correlation exceeds this (in magnitude) are ones the
data (or a plan) cannot separate: they pin down their combination, not each."""


INFORMATION_RATIO_MIN = 0.01
"""Below this ratio of the data's information to the prior's, a parameter is prior-only: the data
would narrow its interval by less than half a percent."""


def unflown(maneuvers, spec: ModelSpec) -> dict:
    """Channel-model terms no maneuver informs, with the reason: a scale-factor branch needs a
    maneuver about its channel's axis in its direction (a symmetric one, in either); a misalignment toward axis b needs a
    maneuver about b (either direction)."""
    flown = {(d.axis, sign) for d in maneuvers for sign in (("+", "-") if d.direction == "both" else (d.direction,))}
    rotated = {d.axis for d in maneuvers}
    reasons = {}
    for p in spec.parameters[spec.core]:
        axis = spec.channels[p.channel].axis
        if p.name in ("sf_pos", "sf_neg"):
            sign = "+" if p.name == "sf_pos" else "-"
            if (axis, sign) not in flown:
                reasons[p.label] = f"no {sign}{axis} maneuver"
        elif p.name == "sf" and axis not in rotated:
            reasons[p.label] = f"no {axis} maneuver"
        elif p.name.startswith("mis_") and p.name[4:] not in rotated:
            reasons[p.label] = f"no {p.name[4:]} maneuver"
    return reasons


def uninformed(stats: Stats, spec: ModelSpec) -> dict:
    """Parameters not yet prior-only whose own information in the data (``stats.A``, the nuisance
    integrated out), relative to their prior's, is below `INFORMATION_RATIO_MIN`."""
    ratio = np.diag(stats.A) * spec.prior_sd_si**2
    return {spec.labels[i]: (f"the data carry {ratio[i]:.2g} of its prior's information: is its regressor "
                             "constant over the maneuvers, or a copy of the bias?")
            for i in np.flatnonzero((ratio < INFORMATION_RATIO_MIN) & spec.free)}


def confounded_pairs(cov: np.ndarray, free: np.ndarray, labels, threshold: float = CORRELATION_MAX) -> list:
    """``(label_i, label_j, correlation)`` of the free parameters correlated beyond ``threshold``."""
    sd = np.sqrt(np.diag(cov))
    corr = cov / np.outer(sd, sd)
    i, j = np.triu_indices(len(cov), 1)
    hit = free[i] & free[j] & (np.abs(corr[i, j]) > threshold)
    return [(labels[a], labels[b], float(corr[a, b])) for a, b in zip(i[hit], j[hit])]
