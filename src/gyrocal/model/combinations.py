"""What the data pin down: per channel the mean scale factor and the asymmetry, and the directions
of the channel parameters left to the prior.

On real data ``sf_pos`` and ``sf_neg`` of one channel are strongly anti-correlated (a +rotation and
a -rotation each inform the sum better than the difference), so each has a wide interval while
their mean is well known. The combinations are linear in the parameters, so their draws are the
parameters' draws times a weight vector (the correlation is honoured), and where no posterior
exists (a plan) their sd is ``sqrt(a' C a)`` of the predicted covariance. A combination is
*resolved* when its posterior sd is at most `RESOLVED_RATIO_MAX` of its prior sd, the prior sd
following from the parameters' declared priors (`ModelSpec`), independent a priori.

Definitions (in ppm, the scale factors' unit):

- ``sf_mean = (sf_pos + sf_neg) / 2``; in a model with one symmetric ``sf`` per channel,
  ``sf_mean = sf``.
- ``sf_asym = sf_pos - sf_neg`` (the conventional asymmetry); a symmetric model does not
  estimate it, and has no ``sf_asym`` row.

With ``mounting: estimate`` the reference is first aligned to the gyros (`gyrocal.checks.mounting`):
that alignment takes up the rotation the gyro triad shares with the reference, so about each body
axis the triad's rotation (half the difference of two opposite misalignments) is not separable
from the mounting; their sum (the triad's non-orthogonality) is. `mounting_separability` shows it
from the covariance: the data's information with a free rotation of the triad integrated out.
"""

from dataclasses import dataclass

import numpy as np

from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import AXES

__all__ = [
    "COMBINATION_NAMES",
    "NAMED",
    "RESOLVED_RATIO_MAX",
    "TURNED_MIN_DEG",
    "Combination",
    "advice",
    "channel_sentence",
    "combination_draws",
    "combination_values",
    "crlb_sd",
    "data_information",
    "directions",
    "flown_directions",
    "mounting_separability",
    "prior_relative",
    "prior_sd",
    "scale_combinations",
    "triad_rotation",
    "weights",
]

RESOLVED_RATIO_MAX = 0.5
"""A combination (or parameter) counts as resolved when its posterior sd is at most this share of its
prior sd: the data then carry at least three times the prior's information about it."""

COMBINATION_NAMES = ("sf_mean", "sf_asym")
"""The derived rows of ``calibration.csv`` (docs/interface.md section 5)."""


@dataclass(frozen=True)
class Combination:
    """One linear combination of a channel's parameters, ``sum(weights * theta)`` in the parameters' unit."""

    label: str
    """``<channel>.<name>``, as the parameters' labels."""
    owner: str
    name: str
    unit: str
    weights: np.ndarray
    """Over the spec's parameters, in their units."""
    prior_only: bool
    """Every parameter it is made of is prior-only (no maneuver informs it)."""


def scale_combinations(spec: ModelSpec) -> list:
    """Per channel, in channel order: ``sf_mean`` and ``sf_asym`` from ``sf_pos`` and ``sf_neg``, or
    ``sf_mean`` alone from a symmetric ``sf``; a channel with neither has none."""
    out = []
    for channel in spec.channels:
        own = {p.name: i for i, p in enumerate(spec.parameters) if p.owner == channel.name}
        terms = {}
        if "sf_pos" in own and "sf_neg" in own:
            terms = {"sf_mean": {own["sf_pos"]: 0.5, own["sf_neg"]: 0.5},
                     "sf_asym": {own["sf_pos"]: 1.0, own["sf_neg"]: -1.0}}
        elif "sf" in own:
            terms = {"sf_mean": {own["sf"]: 1.0}}
        for name, parts in terms.items():
            w = np.zeros(len(spec))
            w[list(parts)] = list(parts.values())
            unit = spec.parameters[next(iter(parts))].unit
            out.append(Combination(f"{channel.name}.{name}", channel.name, name, unit, w,
                                   all(spec.parameters[i].prior_only for i in parts)))
    return out


def combination_values(values: dict) -> dict:
    """A channel's combinations from its parameters' values (``{name: value}``, e.g. a simulation's
    truth): ``sf_mean`` and ``sf_asym`` by their definitions; empty where it has no scale factor."""
    if "sf_pos" in values and "sf_neg" in values:
        return {"sf_mean": (values["sf_pos"] + values["sf_neg"]) / 2, "sf_asym": values["sf_pos"] - values["sf_neg"]}
    return {"sf_mean": values["sf"]} if "sf" in values else {}


def weights(combinations) -> np.ndarray:
    """(K, P): the combinations' weight vectors as rows."""
    return np.array([c.weights for c in combinations]).reshape(len(combinations), -1)


def combination_draws(values: np.ndarray, combinations) -> np.ndarray:
    """Draws of the combinations from draws of the parameters (last axis, in their units)."""
    return np.asarray(values) @ weights(combinations).T


def prior_sd(combinations, spec: ModelSpec) -> np.ndarray:
    """Each combination's prior sd, from its parameters' declared (independent) priors."""
    return np.sqrt(weights(combinations) ** 2 @ np.array([p.prior_sd for p in spec.parameters]) ** 2)


def prior_relative(cov_unit: np.ndarray, w: np.ndarray, prior_sd: np.ndarray) -> tuple:
    """``(sd, prior sd, ratio)`` of the combinations ``w`` (K, P) under a covariance in the parameters'
    units: ``sqrt(a' C a)``, and the same under the independent declared priors."""
    sd = np.sqrt(np.maximum(np.einsum("kp,pq,kq->k", w, cov_unit, w), 0.0))
    prior = np.sqrt(w**2 @ np.asarray(prior_sd, dtype=float) ** 2)
    return sd, prior, sd / prior


def crlb_sd(A_si: np.ndarray, spec: ModelSpec, combinations, null_fraction: float = 1e-12) -> np.ndarray:
    """Cramér-Rao bound (no prior) of each combination from the Fisher information ``A_si`` of the
    spec's parameters (SI): ``sqrt(g' A^+ g)`` over the free parameters, infinite where the
    combination loads on a direction the data leave uninformed (as `gyrocal.planning.plan.crlb_sd`)."""
    free = spec.free
    out = np.full(len(combinations), np.inf)
    idx = np.flatnonzero(free)
    w = weights(combinations)
    if not len(idx) or not np.any(A_si[np.ix_(idx, idx)]):
        return out
    scale = spec.prior_sd_si[idx]
    values, vectors = np.linalg.eigh(A_si[np.ix_(idx, idx)] * np.outer(scale, scale))
    null = values <= null_fraction * values.max()
    g = w[:, idx] * (scale / spec.si_per_unit[idx])
    loading = g @ vectors
    informed = ~np.any(np.abs(loading[:, null]) > 1e-6 * np.linalg.norm(g, axis=1, keepdims=True), axis=1)
    informed &= ~np.any(w[:, ~free] != 0, axis=1)
    var = (loading[:, ~null] ** 2) @ (1.0 / values[~null])
    return np.where(informed, np.sqrt(var), np.inf)


def directions(cov_unit: np.ndarray, prior_sd: np.ndarray, free: np.ndarray | None = None) -> tuple:
    """The eigen-directions of the posterior relative to the prior: in prior-scaled coordinates
    (each parameter over its prior sd) the eigenvectors of the posterior covariance, with the ratio
    of posterior to prior sd along each, smallest first. A ratio near 1 is a direction left to the
    prior; a small one, a direction the data pin down. Prior-only parameters are left out."""
    prior_sd = np.asarray(prior_sd, dtype=float)
    keep = np.ones(len(prior_sd), dtype=bool) if free is None else np.asarray(free, dtype=bool)
    scaled = cov_unit[np.ix_(keep, keep)] / np.outer(prior_sd[keep], prior_sd[keep])
    values, vectors = np.linalg.eigh((scaled + scaled.T) / 2)
    full = np.zeros((len(prior_sd), len(values)))
    full[keep] = vectors
    return np.sqrt(np.maximum(values, 0.0)), full


def data_information(cov_unit: np.ndarray, prior_sd: np.ndarray) -> np.ndarray:
    """The data's information in prior-scaled coordinates: the posterior precision less the prior's
    (the identity there), its eigenvalues clipped at zero (a covariance from draws is noisy)."""
    prior_sd = np.asarray(prior_sd, dtype=float)
    scaled = cov_unit / np.outer(prior_sd, prior_sd)
    values, vectors = np.linalg.eigh((scaled + scaled.T) / 2)
    info = 1.0 / np.maximum(values, 1e-12) - 1.0
    return (vectors * np.maximum(info, 0.0)) @ vectors.T


def triad_rotation(spec: ModelSpec) -> np.ndarray:
    """(P, 3): the change of every misalignment (arcsec) for a small rotation of the whole gyro triad
    about each body axis (arcsec). A channel along ``a`` turned by ``phi`` about ``k`` gains
    ``phi (e_k x e_a)``: toward ``b`` the Levi-Civita sign of (k, a, b)."""
    out = np.zeros((len(spec), 3))
    for i, p in enumerate(spec.parameters):
        if p.core and p.name.startswith("mis_") and p.channel is not None:
            a, b = spec.channels[p.channel].axis_index, AXES.index(p.name[4:])
            k = 3 - a - b
            out[i, k] = float(np.cross(np.eye(3)[k], np.eye(3)[a])[b])
    return out


def mounting_separability(cov_unit: np.ndarray, spec: ModelSpec) -> list:
    """Per body axis: the triad's rotation about it (the mean of the misalignments a turn about it
    moves, each signed as the turn moves it; for one triad half the difference of the two opposite
    misalignments) and each pair's non-orthogonality (the sum of two opposite misalignments, to first
    order 90 deg less the angle between their sensing axes, as `orthogonality` and ``orthogonality.csv`` give it),
    with the posterior sd over the prior's as fitted (mounting taken as known) and with the
    mounting free: the data's information (`data_information`) with a turn of the triad about
    every axis integrated out. A combination the mounting takes up has a ratio near 1 there: not
    separable from it."""
    prior_sd = np.array([p.prior_sd for p in spec.parameters])
    idx = np.flatnonzero(spec.free & (prior_sd > 0))
    rot = triad_rotation(spec)[idx]
    whitened = rot / prior_sd[idx, None]
    info = data_information(cov_unit[np.ix_(idx, idx)], prior_sd[idx])
    seen = whitened.T @ info @ whitened
    info_free = info - info @ whitened @ np.linalg.pinv(seen, rcond=1e-10) @ whitened.T @ info
    covariances = {"ratio_fitted": cov_unit[np.ix_(idx, idx)] / np.outer(prior_sd[idx], prior_sd[idx]),
                   "ratio_mounting_free": np.linalg.inv(info_free + np.eye(len(idx)))}

    def row(axis, kind, w, text):
        g = w * prior_sd[idx]
        prior = np.linalg.norm(g)
        return {"axis": axis, "kind": kind, "combination": text,
                **{key: float(np.sqrt(max(g @ c @ g, 0.0)) / prior) for key, c in covariances.items()}}

    rows = []
    for k, axis in enumerate(AXES):
        moved = np.flatnonzero(rot[:, k])
        if not len(moved):
            continue
        terms = " ".join(f"{'+' if rot[i, k] > 0 else '-'} {spec.labels[idx[i]]}" for i in moved)
        terms = terms.removeprefix("+ ").replace("- ", "-", 1) if terms.startswith("- ") else terms.removeprefix("+ ")
        rows.append(row(axis, "rotation", rot[:, k] / np.sum(rot[:, k] ** 2), f"({terms}) / {len(moved)}"))
        for i in np.flatnonzero(rot[:, k] > 0):
            for j in np.flatnonzero(rot[:, k] < 0):
                w = np.zeros(len(idx))
                w[[i, j]] = 1.0
                rows.append(row(axis, "non-orthogonality", w, f"{spec.labels[idx[i]]} + {spec.labels[idx[j]]}"))
    return rows


TURNED_MIN_DEG = 10.0
"""A direction (an axis, one way) the data hold: the body turned about it at least this far, summed
over the maneuvers (a limit cycle's wander adds up to a degree or so over a campaign)."""


def flown_directions(maneuvers, min_deg: float = TURNED_MIN_DEG) -> set:
    """``(axis, sign)`` the body turned about at least ``min_deg`` over ``maneuvers``: the motion
    (each maneuver's ``turned()``, `gyrocal.maneuvers.preprocess.ManeuverData.turned`), labelled or
    free alike; a maneuver known only by its label (no data) counts as turning as labelled."""
    total = {}
    for d in maneuvers:
        if hasattr(d, "turned"):
            for key, angle in d.turned().items():
                total[key] = total.get(key, 0.0) + angle
        elif d.axis is not None:
            for sign in ("+", "-") if d.direction == "both" else (d.direction,):
                total[(d.axis, sign)] = np.inf
    return {key for key, angle in total.items() if np.rad2deg(angle) >= min_deg}


def advice(name: str, axis: str, flown: set) -> str:
    """The motion that would resolve a channel's unresolved ``sf_mean``, ``sf_asym`` or misalignment
    ``mis_<toward>`` (``axis``: the channel's own), from what the data turned (`flown_directions`):
    a turn the data lack by name, one they hold as more of it. Turned both ways, the asymmetry is
    the hard part: at one rate in both directions, ``sf_pos - sf_neg`` adds the same error rate as
    a bias does (``sf_pos w`` one way, ``-sf_neg w`` back), so only rest or a change of rate tells
    them apart."""
    if name.startswith("mis_"):
        toward = name[4:]
        if not any(a == toward for a, _ in flown):
            return f"turn about {toward}, either way (the data hold no such turn)"
        return f"turn more, or larger, about {toward}"
    missing = [s for s in "+-" if (axis, s) not in flown]
    if len(missing) == 2:
        return f"turn about +{axis} and -{axis}, as far each way"
    if missing:
        return f"turn about {missing[0]}{axis} (the data turn only {'+-'.replace(missing[0], '')}{axis})"
    if name == "sf_asym":
        return (f"turn about +{axis} and -{axis} with rest before, between and after the turns, or at "
                f"two rates: at one rate both ways sf_pos - sf_neg reads as a bias")
    return f"turn more, or larger, about +{axis} and -{axis}, as far each way"


NAMED = {"sf_mean": "sf_mean", "sf_asym": "sf_asym (sf_pos - sf_neg)"}
"""How a sentence names a combination."""


def channel_sentence(channel, rows, flown: set) -> str:
    """One sentence of a channel: which of its combinations and misalignments are resolved, which
    are informed but still too wide to act on, which are not resolved, and which maneuver would
    resolve each of the last two. ``rows`` are dicts with ``parameter``, ``sd``, ``ratio`` (sd over
    the prior's), ``unit`` and optionally ``width`` (of the 95 % interval) and ``limit`` (the widest
    interval acceptable in that unit)."""
    good, wide, bad = [], [], []

    def number(value):
        return f"{value:.0f}" if abs(value) >= 100 else f"{value:.3g}"

    for r in rows:
        name = NAMED.get(r["parameter"], r["parameter"])
        todo = advice(r["parameter"], channel.axis, flown)
        if not r["ratio"] <= RESOLVED_RATIO_MAX:
            bad.append(f"{name} is not (sd {number(r['sd'])} {r['unit']}, {r['ratio']:.2f} of its prior's): {todo}")
        elif r.get("limit") is not None and r["width"] > r["limit"]:
            wide.append(f"{name} is informed ({r['ratio']:.2f} of its prior's sd) but its 95 % interval is "
                        f"{number(r['width'])} {r['unit']} wide, over the {r['limit']:g} {r['unit']} limit: {todo}")
        else:
            good.append(f"{r['parameter']} (sd {number(r['sd'])} {r['unit']})")
    text = f"{channel.name}: " + (("resolved " + ", ".join(good)) if good else "nothing resolved")
    return text + ("; " + "; ".join(wide + bad) if wide or bad else "") + "."
