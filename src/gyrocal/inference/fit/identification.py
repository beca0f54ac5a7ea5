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

from gyrocal.inference.fit.likelihood import Stats
from gyrocal.model.spec import ModelSpec

__all__ = [
    "CONDITION_MAX", "CORRELATION_MAX", "DETECTION_SD", "INFORMATION_RATIO_MIN", "confounded_pairs", "joint_information",
    "maneuver_to_fly", "prior_held_directions", "unflown", "uninformed"
]

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


def joint_information(A: np.ndarray, prior_sd: np.ndarray) -> np.ndarray:
    """Each parameter's information in the data relative to its prior's, the others estimated with it:
    ``prior_var / posterior_var - 1`` from the data's information ``A`` (nuisance integrated out) and
    the priors. Where a column is its own, this is ``A_ii prior_sd_i^2``; where the data pin down only
    a combination of two parameters, neither alone is informed, however large its own column."""
    scaled = A * np.outer(prior_sd, prior_sd)
    posterior = np.linalg.inv(scaled + np.eye(len(A)))
    return 1.0 / np.diag(posterior) - 1.0


def uninformed(stats: Stats, spec: ModelSpec) -> dict:
    """Parameters not yet prior-only whose information in the data (``stats.A``, the nuisance
    integrated out), relative to their prior's, is below `INFORMATION_RATIO_MIN`: first those whose
    own column carries none, then, one at a time, the one the data inform least once the others are
    estimated with it (`joint_information`), until every other carries that much."""
    ratio = np.diag(stats.A) * spec.prior_sd_si**2
    reasons = {spec.labels[i]: (f"the data carry {ratio[i]:.2g} of its prior's information: is its regressor "
                                "constant over the maneuvers, or a copy of the bias?")
               for i in np.flatnonzero((ratio < INFORMATION_RATIO_MIN) & spec.free)}
    free = spec.free & (ratio >= INFORMATION_RATIO_MIN)
    while free.sum() > 1:
        index = np.flatnonzero(free)
        joint = joint_information(stats.A[np.ix_(index, index)], spec.prior_sd_si[index])
        weakest = int(np.argmin(joint))
        if joint[weakest] >= INFORMATION_RATIO_MIN:
            break
        i = index[weakest]
        reasons[spec.labels[i]] = (f"the data carry {joint[weakest]:.2g} of its prior's information once the "
                                   f"others are estimated with it (its own column: {ratio[i]:.2g}): only a "
                                   f"combination with them is measured; {maneuver_to_fly(spec, i)}")
        free[i] = False
    return reasons


CONDITION_MAX = 1e6
"""A direction of the parameters (scaled by their prior sds) that the data inform this many times
less than their best-informed one, and less than the prior does, is held by the prior alone."""


def prior_held_directions(A: np.ndarray, prior_sd: np.ndarray, labels, top: int = 3) -> list:
    """Directions of the parameters (``labels``; scaled by ``prior_sd``) the data leave to the prior:
    the data's information along them is below the prior's and `CONDITION_MAX` times below its largest.
    Each as ``(information, [(label, loading), ...])``, its ``top`` largest loadings first."""
    scaled = A * np.outer(prior_sd, prior_sd)
    values, vectors = np.linalg.eigh(scaled)
    out = []
    for value, vector in zip(values, vectors.T):
        if value < 1.0 and value * CONDITION_MAX < values[-1]:
            order = np.argsort(-np.abs(vector))[:top]
            out.append((float(value), [(labels[k], float(vector[k])) for k in order]))
    return out


def maneuver_to_fly(spec: ModelSpec, i: int) -> str:
    """What to fly to inform parameter ``i``: a scale-factor branch needs turns about its channel's axis
    in its direction, a misalignment toward b turns about b (larger, faster or longer ones)."""
    p = spec.parameters[i]
    if p.channel is None:
        return "fly maneuvers that excite it"
    axis = spec.channels[p.channel].axis
    if p.name in ("sf_pos", "sf_neg"):
        return f"fly larger or faster {'+' if p.name == 'sf_pos' else '-'}{axis} maneuvers"
    if p.name.startswith("mis_"):
        return f"fly larger or faster maneuvers about {p.name[4:]} (both directions)"
    return f"fly maneuvers about {axis} that excite it"


def confounded_pairs(cov: np.ndarray, free: np.ndarray, labels, threshold: float = CORRELATION_MAX) -> list:
    """``(label_i, label_j, correlation)`` of the free parameters correlated beyond ``threshold``."""
    sd = np.sqrt(np.diag(cov))
    corr = cov / np.outer(sd, sd)
    i, j = np.triu_indices(len(cov), 1)
    hit = free[i] & free[j] & (np.abs(corr[i, j]) > threshold)
    return [(labels[a], labels[b], float(corr[a, b])) for a, b in zip(i[hit], j[hit])]
