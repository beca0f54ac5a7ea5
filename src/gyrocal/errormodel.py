"""The attitude-error model and its Jacobian, per maneuver.

For a linearisation point (channel parameters and this maneuver's biases) each channel
set's gyro attitude is propagated and compared with the star tracker (eq. 4). The
error is rotated into the inertial frame, ``z_j = R(t_j) e_j``, where a parameter
change acts additively: a change ``d phi_k`` of the k-th body increment turns every
later attitude by ``R_{k+1/2} d phi_k``. Hence, to first order,

    z_j = chi0 + S_j (p_true - p0) + gyro random walk + R_j v_j,

with ``chi0`` the initial attitude error and ``v_j`` the star-tracker noise.
"""

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from . import channels as ch
from . import kinematics
from .effects import ManeuverView
from .preprocess import ManeuverData


@dataclass
class Linearization:
    """One maneuver's residuals and design, all sets stacked (M samples, S sets)."""

    maneuver: str
    sets: list
    z: np.ndarray
    """(M, S, 3) inertial-frame error of the star tracker relative to each set's attitude (rad)."""
    design: np.ndarray
    """(M, S, 3, P) derivative of z with respect to the global channel parameters."""
    bias_design: np.ndarray
    """(M, S, 3, n_channels) derivative of z with respect to this maneuver's channel biases."""
    st_matrix: np.ndarray
    """(M, 3, 3) body-to-inertial matrices at the star-tracker times (first set)."""
    st_dt: np.ndarray
    """(M,) time since the previous star-tracker sample (the first: since t0)."""
    shared_walk: np.ndarray
    """(M, S, S, 3, 3) per-interval random-walk covariance of the sets per unit ARW^2."""
    body_error: np.ndarray
    """(M, S, 3) the same error in body axes (rad), for plots and diagnostics."""


def effect_regressors(data: ManeuverData, extras):
    """What the extra effects change, per unit parameter (SI), at nominal parameters.

    Returns (K, n_channels, E) changes of the raw channel increments and (M, 3, E)
    changes of the body-frame star-tracker error.
    """
    n_ch = len(data.channels)
    gyro = np.zeros((len(data.dt), n_ch, len(extras)))
    star = np.zeros((len(data.st_time), 3, len(extras)))
    if not extras:
        return gyro, star
    zeros = ch.ChannelParams.zeros(data.channels)
    first = data.sets[0]
    view = ManeuverView(data, ch.solve_body(data.set_increments(first), zeros.subset(first), dt_s=data.dt)
                        / data.dt[:, None])
    cache = {}
    for j, extra in enumerate(extras):
        effect = extra.effect
        if effect.name not in cache:
            try:
                cache[effect.name] = (effect.gyro(view), effect.star_tracker(view))
            except KeyError as exc:
                raise ValueError(f"effect {effect.name} needs {exc} in maneuver {data.id}, which has the "
                                 f"extra gyro.csv columns {sorted(data.extras)}") from exc
        g, s = cache[effect.name]
        name = extra.parameter.name
        if name in g:
            column = np.asarray(g[name], dtype=float).reshape(len(data.dt), n_ch)
            if extra.channel is None:
                gyro[:, :, j] = column
            else:
                gyro[:, extra.channel, j] = column[:, extra.channel]
        if name in s:
            star[:, :, j] = np.asarray(s[name], dtype=float).reshape(len(data.st_time), 3)
    return gyro, star


def _set_jacobian(data: ManeuverData, channel_set, params: ch.ChannelParams, regressors, extra_values):
    """Propagate one set and return attitudes, increments and d(phi)/d(set params).

    ``regressors`` (K, 3, E) are the extra effects' changes of this set's channel
    increments per unit parameter; the model removes ``regressors @ extra_values``.
    """
    sub = params.subset(channel_set)
    dt = data.dt
    u = data.set_increments(channel_set) - regressors @ extra_values
    phi = ch.solve_body(u, sub, dt_s=dt)
    attitudes = kinematics.propagate(Rotation.from_quat(data.attitude0_quat), phi)
    positive = (u - np.outer(dt, sub.bias_rad_s)) > 0
    scale = 1.0 + np.where(positive, sub.sf_pos, sub.sf_neg)
    rows = ch.response_rows(sub)
    m_inv = np.linalg.inv(scale[:, :, None] * rows[None])
    sensed = phi @ rows.T
    columns = []
    for i, c in enumerate(sub.channels):
        w = -m_inv[:, :, i]
        columns.append(w * (sensed[:, i] * positive[:, i])[:, None])
        columns.append(w * (sensed[:, i] * ~positive[:, i])[:, None])
        for b in c.other_axes:
            columns.append(w * (scale[:, i] * phi[:, ch.AXIS_INDEX[b]])[:, None])
    for i in range(3):
        columns.append(-m_inv[:, :, i] * dt[:, None])
    for j in range(regressors.shape[2]):
        columns.append(-np.einsum("kai,ki->ka", m_inv, regressors[:, :, j]))
    return attitudes, phi, np.stack(columns, axis=2)


def linearize(data: ManeuverData, params: ch.ChannelParams, extras=(), extra_values=None) -> Linearization:
    """Residuals and Jacobian of one maneuver about ``params`` (all channels; biases are
    this maneuver's) and, for the extra effects, about ``extra_values`` (SI)."""
    sets = data.sets
    names = [c.name for c in params.channels]
    n_base = ch.N_PARAMS_PER_CHANNEL * len(names)
    n_par = n_base + len(extras)
    extra_values = np.zeros(len(extras)) if extra_values is None else np.asarray(extra_values, dtype=float)
    gyro_reg, star_reg = effect_regressors(data, extras)
    st_rot = Rotation.from_quat(data.st_quat)
    k, frac = data.st_interval()
    m = len(data.st_time)
    z = np.empty((m, len(sets), 3))
    body = np.empty((m, len(sets), 3))
    design = np.zeros((m, len(sets), 3, n_par))
    bias_design = np.zeros((m, len(sets), 3, len(names)))
    for s, channel_set in enumerate(sets):
        slots = [names.index(n) for n in channel_set]
        attitudes, phi, dphi = _set_jacobian(data, channel_set, params, gyro_reg[:, slots, :], extra_values)
        mid = kinematics.compose(attitudes[:-1], Rotation.from_rotvec(0.5 * phi))
        inertial = np.einsum("kij,kjp->kip", mid.as_matrix(), dphi)
        at_st_jac = cumulative_at_st(inertial, k, frac)
        at_st = kinematics.attitude_at(data.gyro_time, attitudes, phi, data.st_time)
        e = kinematics.error_angles_rad(at_st, st_rot)
        st_columns = np.einsum("mab,mbe->mae", at_st.as_matrix(), star_reg)
        body[:, s] = e - star_reg @ extra_values
        z[:, s] = at_st.apply(e) - st_columns @ extra_values
        for slot, name in enumerate(channel_set):
            j = names.index(name)
            design[:, s, :, 4 * j:4 * j + 4] = at_st_jac[:, :, 4 * slot:4 * slot + 4]
            bias_design[:, s, :, j] = at_st_jac[:, :, 12 + slot]
        design[:, s, :, n_base:] = at_st_jac[:, :, 15:] + st_columns
        if s == 0:
            st_matrix = at_st.as_matrix()
    st_dt = np.diff(np.concatenate([[data.gyro_time[0]], data.st_time]))
    shared = _shared_walk(len(sets), st_dt)
    return Linearization(data.id, sets, z, design, bias_design, st_matrix, st_dt, shared, body)


def cumulative_at_st(per_interval: np.ndarray, k: np.ndarray, frac: np.ndarray) -> np.ndarray:
    """Running sum of per-gyro-interval terms, evaluated at the star-tracker samples
    (a sample inside interval k has the sum of the intervals before it plus its share)."""
    cumulative = np.concatenate([np.zeros((1,) + per_interval.shape[1:]), np.cumsum(per_interval, axis=0)])
    return cumulative[k] + frac.reshape((-1,) + (1,) * (per_interval.ndim - 1)) * per_interval[k]


def _shared_walk(n_sets, st_dt):
    """Random-walk covariance per star-tracker interval, per unit ARW^2 (rad^2/s).

    Within a set the walk is isotropic (``dt I``); the sets share no channel
    (`channels.channel_sets`), so their walks are independent.
    """
    out = np.zeros((len(st_dt), n_sets, n_sets, 3, 3))
    for s in range(n_sets):
        out[:, s, s] = st_dt[:, None, None] * np.eye(3)
    return out
