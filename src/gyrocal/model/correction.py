"""The gyro correction matrices to uplink, one pair (positive, negative) per channel set.

Convention, written into the file itself: for a channel set ordered roll, pitch, yaw,
with bias-free channel rates ``w`` (rad/s), the corrected body rate is

    omega_body = M @ diag(k) @ w,

``M = (I + N)^-1`` the misalignment correction (``N[i, b]`` the misalignment of the
set's channel i toward axis b) and ``k_i = 1 / (1 + sf_i)``, with ``sf_pos`` when
``w_i > 0`` and ``sf_neg`` when ``w_i < 0``. ``matrix_pos`` and ``matrix_neg`` are
``M diag(k)`` with every channel on its positive or negative branch: the exact
inverse of the channel model (docs/interface.md section 2) for a single-axis rotation. A
symmetric model's one ``sf`` sets both branches, so its file keeps this format with
``scale_correction_pos`` equal to ``scale_correction_neg``.
"""

import numpy as np

from gyrocal.model import channels as ch
from gyrocal.model.units import AXES

__all__ = ["CONVENTION", "apply", "campaign_correction", "correction_file", "correction_for_set", "flown_sets"]

CONVENTION = ("omega_body = misalignment_correction @ diag(scale_correction) @ w, w the bias-free "
              "rates of the set's channels (roll, pitch, yaw order); scale_correction takes "
              "scale_correction_pos[i] where w[i] > 0 and scale_correction_neg[i] where w[i] < 0. "
              "matrix_pos / matrix_neg: the product with every channel on one branch.")


def correction_for_set(params: ch.ChannelParams, channel_set) -> dict:
    """Correction matrices of one channel set, from channel parameters (SI)."""
    sub = params.subset(channel_set)
    rows = ch.response_rows(sub)
    m_corr = np.linalg.inv(rows)
    k_pos = 1.0 / (1.0 + sub.sf_pos)
    k_neg = 1.0 / (1.0 + sub.sf_neg)
    return {
        "channels": list(channel_set),
        "axes": list(AXES),
        "misalignment_correction": m_corr.tolist(),
        "scale_correction_pos": k_pos.tolist(),
        "scale_correction_neg": k_neg.tolist(),
        "matrix_pos": (m_corr * k_pos[None, :]).tolist(),
        "matrix_neg": (m_corr * k_neg[None, :]).tolist(),
    }


def apply(correction: dict, rates: np.ndarray) -> np.ndarray:
    """Body rates from bias-free channel rates (N, 3) with a correction entry."""
    m = np.asarray(correction["misalignment_correction"])
    k = np.where(rates > 0, correction["scale_correction_pos"], correction["scale_correction_neg"])
    return (rates * k) @ m.T


def correction_file(params: ch.ChannelParams, sets, in_loop_sets, source: str) -> dict:
    """The whole correction document: convention, provenance and one entry per set."""
    entries = []
    for channel_set in sets:
        entry = correction_for_set(params, channel_set)
        entry["in_loop"] = tuple(channel_set) in {tuple(s) for s in in_loop_sets}
        entries.append(entry)
    return {"convention": CONVENTION, "estimate": source, "sets": entries}


def flown_sets(maneuvers) -> list:
    """Every channel set the campaign's maneuvers use (`channels.channel_sets` of each), each once, in
    the order they come: the triads the correction and the non-orthogonality are given for."""
    return list(dict.fromkeys(tuple(s) for d in maneuvers for s in d.sets))


def campaign_correction(params: ch.ChannelParams, maneuvers, source: str) -> dict:
    """`correction_file` for every channel set the campaign's maneuvers use (`flown_sets`); a set is in
    the loop where some maneuver flew with it selected onboard."""
    in_loop = {tuple(d.sets[0]) for d in maneuvers}
    return correction_file(params, flown_sets(maneuvers), in_loop, source)
