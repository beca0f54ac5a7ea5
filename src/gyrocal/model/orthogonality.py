"""The non-orthogonality of each channel set: how far the angle between two of its sensing axes is
from 90 deg, the part of the misalignments that no choice of reference frame changes.

Channel c along body axis a senses the body rate along ``u_c = e_a + m_c`` (the row of the paper's
[M], eq. 3; docs/interface.md section 2), whatever its scale factor. A small turn of the whole triad
by ``phi`` about axis k adds ``phi (e_k x e_a)`` to ``m_c`` (`combinations.triad_rotation`): it moves
``m_ab`` and ``m_ba`` by opposite amounts, so their antisymmetric part is the triad's rotation, which
an estimated mounting takes up, and their sum is what is left. That sum is, to first order, the
departure from 90 deg of the angle between the two sensing axes, and the angle itself is unchanged
by any rotation. So, for the channels i (axis a) and j (axis b) of one channel set::

    nonorth_ab = 90 deg - angle(u_i, u_j) = arcsin(u_i . u_j / (|u_i| |u_j|)) ~= m_ib + m_ja

positive where the two sensing axes lean toward each other. Computed exactly from the rows (the
approximation's error is of second order in the misalignments: under an arcsec for a few hundred
arcsec). The channel sets are the campaign's, as `channels.channel_sets` forms them and the
correction file lists them (docs/interface.md, sections 1 and 5): one per DTG selection on MOM
(selected and redundant), the one triad of a three-axis MEMS unit.
"""

from dataclasses import dataclass

import numpy as np

from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import AXES, AXIS_INDEX, rad_to_arcsec

__all__ = ["NAME", "Pair", "nonorthogonality_rad", "pair_draws", "pairs", "sensing_axes"]

NAME = "nonorth"
"""A pair's parameter name is ``nonorth_<axis a>_<axis b>`` (body-axis order), in arcsec."""


def sensing_axes(mis_rad, axis_index) -> np.ndarray:
    """(..., n, 3) unit vectors of the channels' sensing axes from their misalignments (..., n, 3),
    rad, toward each body axis (the own axis's entry ignored): ``(e_a + m_c) / |e_a + m_c|``."""
    rows = np.array(mis_rad, dtype=float, copy=True)
    n = rows.shape[-2]
    rows[..., np.arange(n), np.asarray(axis_index)] = 1.0
    return rows / np.linalg.norm(rows, axis=-1, keepdims=True)


def nonorthogonality_rad(axis_i: np.ndarray, axis_j: np.ndarray) -> np.ndarray:
    """90 deg less the angle between two unit vectors (..., 3), rad: positive where they lean toward
    each other."""
    return np.arcsin(np.clip(np.sum(axis_i * axis_j, axis=-1), -1.0, 1.0))


@dataclass(frozen=True)
class Pair:
    """Two channels of one channel set, along two different body axes."""

    set: str
    """The channel set, its channels joined by ``+`` in roll, pitch, yaw order (as ``fit.csv``)."""
    channels: tuple
    """Its two channels, in body-axis order."""
    axes: tuple
    """Their two axes, in body-axis order."""
    parameters: tuple
    """Per channel, the indices of its misalignments in the spec, toward roll, pitch, yaw (-1: its own
    axis, or a misalignment the model lacks)."""
    prior_only: bool
    """The two misalignments it is made of to first order (``m_ab``, ``m_ba``) are both prior-only."""

    @property
    def name(self) -> str:
        return f"{NAME}_{self.axes[0]}_{self.axes[1]}"

    @property
    def label(self) -> str:
        return f"{self.channels[0]}+{self.channels[1]}.{self.name}"

    @property
    def definition(self) -> str:
        """The first-order sum it stands for, in the parameters' labels."""
        (a, b), (i, j) = self.axes, self.channels
        return f"{i}.mis_{b} + {j}.mis_{a}"


def pairs(spec: ModelSpec, sets) -> list:
    """The pairs of every channel set in ``sets`` (tuples of channel names, ordered roll, pitch, yaw,
    as `channels.channel_sets` gives them), each pair once, in the sets' order; none for a model
    without misalignments."""
    index = {label: i for i, label in enumerate(spec.labels)}
    if not any(label.split(".", 1)[1].startswith("mis_") for label in index):
        return []
    by_name = {c.name: c for c in spec.channels}
    out, seen = [], set()
    for channel_set in sets:
        ordered = sorted(channel_set, key=lambda n: by_name[n].axis_index)
        for x in range(len(ordered)):
            for y in range(x + 1, len(ordered)):
                i, j = ordered[x], ordered[y]
                if (i, j) in seen or by_name[i].axis == by_name[j].axis:
                    continue
                seen.add((i, j))
                columns = tuple(tuple(index.get(f"{c}.mis_{b}", -1) for b in AXES) for c in (i, j))
                a, b = by_name[i].axis, by_name[j].axis
                first = [columns[0][AXIS_INDEX[b]], columns[1][AXIS_INDEX[a]]]
                prior_only = all(k < 0 or spec.parameters[k].prior_only for k in first)
                out.append(Pair("+".join(channel_set), (i, j), (a, b), columns, prior_only))
    return out


def pair_draws(values, spec: ModelSpec, pairs_) -> np.ndarray:
    """(..., K) each pair's non-orthogonality (arcsec) from draws of the spec's parameters (last axis,
    in their units, as ``posterior.nc``'s ``channel_param``): draw by draw, so that the correlation of
    the misalignments is honoured."""
    values = np.asarray(values, dtype=float)
    si = values * spec.si_per_unit
    out = np.empty(values.shape[:-1] + (len(pairs_),))
    for k, p in enumerate(pairs_):
        mis = np.zeros(values.shape[:-1] + (2, 3))
        for c, columns in enumerate(p.parameters):
            for b, col in enumerate(columns):
                if col >= 0:
                    mis[..., c, b] = si[..., col]
        unit = sensing_axes(mis, [AXIS_INDEX[a] for a in p.axes])
        out[..., k] = rad_to_arcsec(nonorthogonality_rad(unit[..., 0, :], unit[..., 1, :]))
    return out

