"""Which parameters the maneuvers can inform at all; the others are prior-only.

A scale factor of a direction the body never turned, or a misalignment toward an axis it never
turned about, has no column in the data that is not noise (the motion decides, not the
maneuvers' labels: `unflown`): fitted anyway, it takes up noise and
drags the parameters the data do inform. So is a parameter whose column, once the
nuisance (initial attitude, biases) is integrated out, carries almost no information: a
regressor that is constant, or a copy of the bias. Both are marked prior-only and kept
out of the fit (`errormodel.linearize` gives them no column); their posterior is their
prior, and the verdict names them.
"""

import numpy as np

from gyrocal.inference.fit.likelihood import Stats
from gyrocal.maneuvers.preprocess import body_increments
from gyrocal.model import channels as ch
from gyrocal.model.combinations import flown_directions
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import AXIS_INDEX, arcsec_to_rad

__all__ = [
    "CONDITION_MAX",
    "CORRELATION_MAX",
    "DETECTION_SD",
    "INFORMATION_RATIO_MIN",
    "MOTION_RATIO_MIN",
    "MOTION_SIGMA_ARCSEC",
    "confounded_pairs",
    "joint_information",
    "maneuver_to_fly",
    "motion_information",
    "prior_held_directions",
    "unflown",
    "uninformed"
]

DETECTION_SD = 5.0
"""A value counts as beyond a physical bound once it exceeds it by this many of its standard errors."""

CORRELATION_MAX = 0.9
"""Two parameters whose predicted posterior correlation exceeds this (in magnitude) are ones the
data (or a plan) cannot separate: they pin down their combination, not each."""


INFORMATION_RATIO_MIN = 0.01
"""Below this ratio of the data's information to the prior's, a parameter is prior-only: the data
would narrow its interval by less than half a percent."""


MOTION_RATIO_MIN = 1.0
"""Below this ratio of the motion's information to the prior's, a term is prior-only before any fit
(`unflown`): its posterior sd would stay above 0.7 of its prior's, and fitted it takes up noise. A
limit cycle's wander gives a term a few hundredths; a single 90 deg turn at MOM's noise, ten thousand."""

MOTION_SIGMA_ARCSEC = 10.0
"""The reference's noise per sample that `unflown` weighs the motion with where none is stated."""


def motion_information(maneuvers, spec: ModelSpec, sigma_rad: float, arw_rad_sqrt_s: float = 0.0) -> dict:
    """Per channel, the information its scale factors and misalignments draw from the motion alone:
    each term's column is the rotation it multiplies (eq. 3: the channel's own axis, by sign for
    ``sf_pos``/``sf_neg``; the other axis for ``mis_<b>``), accumulated into the error angle at
    the reference's samples, each maneuver's start attitude and bias (a line in time) projected
    out, over the error's noise: the reference's ``sigma_rad`` and the gyro's walk over the window
    (``arw^2 T / 6``, a walk's mean square over T less its line), so that a column made of the gyros'
    own noise (a body at rest about that axis, a precise reference) does not count as motion.
    ``{channel index: (parameter indices, A)}``."""
    out = {}
    columns = {}
    for data in maneuvers:
        inc = body_increments(data, data.sets[0], ch.ChannelParams.zeros(data.channels))
        k, _ = data.st_interval()
        t = data.st_time - data.st_time[0]
        line = np.linalg.qr(np.column_stack([np.ones_like(t), t]))[0]
        weight = 1.0 / np.sqrt(sigma_rad**2 + arw_rad_sqrt_s**2 * (t[-1] if t.size else 0.0) / 6.0)
        for i, p in enumerate(spec.parameters):
            if not p.core or p.channel is None or not _motion_term(p.name):
                continue
            own = inc[:, AXIS_INDEX[spec.channels[p.channel].axis]]
            x = {"sf_pos": own.clip(min=0), "sf_neg": own.clip(max=0), "sf": own}.get(p.name)
            x = inc[:, AXIS_INDEX[p.name[4:]]] if x is None else x
            at_st = np.cumsum(x)[k]
            columns.setdefault(i, []).append(weight * (at_st - line @ (line.T @ at_st)))
    for i, parts in columns.items():
        out.setdefault(spec.parameters[i].channel, []).append((i, np.concatenate(parts)))
    return {c: ([i for i, _ in items], np.array([[a @ b for _, b in items] for _, a in items]))
            for c, items in out.items()}


def _motion_term(name: str) -> bool:
    return name in ("sf_pos", "sf_neg", "sf") or name.startswith("mis_")


def unflown(maneuvers, spec: ModelSpec, stated: dict | None = None) -> dict:
    """Channel-model terms the motion does not inform, with the reason: whatever the maneuvers'
    labels, a scale factor or misalignment whose information in the motion (`motion_information`,
    the others of its channel estimated with it: `joint_information`) is below `MOTION_RATIO_MIN`
    of its prior's (`uninformed` then judges the rest from the data's information at
    `INFORMATION_RATIO_MIN`). ``stated``: the noise knowledge (its star tracker's
    sds, absent `MOTION_SIGMA_ARCSEC`, and its ARW weigh the motion)."""
    stated = stated or {}
    sigma = arcsec_to_rad(np.sqrt((2 * stated.get("sigma_cross_arcsec", MOTION_SIGMA_ARCSEC) ** 2
                                   + stated.get("sigma_about_arcsec", MOTION_SIGMA_ARCSEC) ** 2) / 3))
    held = flown_directions(maneuvers)
    reasons = {}
    arw = np.deg2rad(stated.get("arw_deg_sqrt_h", 0.0)) / 60.0
    for index, A in motion_information(maneuvers, spec, sigma, arw).values():
        joint = joint_information(A, spec.prior_sd_si[index])
        for i, ratio in zip(index, joint):
            if ratio < MOTION_RATIO_MIN:
                missing = [w for w in wanted_turns(spec, i) if (w[1:], w[0]) not in held]
                if len(missing) == 2:
                    reasons[spec.labels[i]] = f"no {missing[0][1:]} turn in the data: turn about {missing[0][1:]}, either way"
                elif missing:
                    reasons[spec.labels[i]] = f"no {missing[0]} turn in the data: turn about {missing[0]}"
                else:
                    reasons[spec.labels[i]] = (f"the motion carries {ratio:.2g} of its prior's information: "
                                               f"{maneuver_to_fly(spec, i, held)}")
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


def wanted_turns(spec: ModelSpec, i: int) -> list:
    """The turns (``+pitch``, ``-yaw``) that inform parameter ``i`` (eq. 3): a scale-factor branch its
    channel's axis in its direction (a symmetric one either way), a misalignment toward b about b,
    either way; none for other parameters."""
    p = spec.parameters[i]
    if p.channel is None:
        return []
    axis = spec.channels[p.channel].axis
    if p.name in ("sf_pos", "sf_neg", "sf"):
        return [f"{s}{axis}" for s in ({"sf_pos": "+", "sf_neg": "-"}.get(p.name) or "+-")]
    if p.name.startswith("mis_"):
        return [f"+{p.name[4:]}", f"-{p.name[4:]}"]
    return []


def maneuver_to_fly(spec: ModelSpec, i: int, held: set | None = None) -> str:
    """The motion that would inform parameter ``i``: a scale-factor branch needs turns about its
    channel's axis in its direction, a misalignment toward b turns about b. With ``held`` (the
    ``(axis, sign)`` the data already turn, `combinations.flown_directions`), a direction the data hold is asked
    for as more of it, one they lack by name."""
    wanted = wanted_turns(spec, i)
    if not wanted:
        p = spec.parameters[i]
        return "turn in ways that excite it" if p.channel is None else \
            f"turn about {spec.channels[p.channel].axis} in ways that excite it"
    if held is None:
        return f"turn more, or faster, about {' and '.join(wanted)}"
    missing = [w for w in wanted if (w[1:], w[0]) not in held]
    if missing:
        return f"turn about {' and '.join(missing)} (the data hold no such turn)"
    return f"turn more, or faster, about {' and '.join(wanted)} (the data's turns there are too small or too slow)"


def confounded_pairs(cov: np.ndarray, free: np.ndarray, labels, threshold: float = CORRELATION_MAX) -> list:
    """``(label_i, label_j, correlation)`` of the free parameters correlated beyond ``threshold``."""
    sd = np.sqrt(np.diag(cov))
    corr = cov / np.outer(sd, sd)
    i, j = np.triu_indices(len(cov), 1)
    hit = free[i] & free[j] & (np.abs(corr[i, j]) > threshold)
    return [(labels[a], labels[b], float(corr[a, b])) for a, b in zip(i[hit], j[hit])]
