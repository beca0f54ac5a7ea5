"""The attitude-error model and its Jacobian, per maneuver.

For a linearisation point (channel parameters and this maneuver's biases) each channel
set's gyro attitude is propagated and compared with the star tracker (eq. 4). The
error is rotated into the inertial frame, ``z_j = R(t_j) e_j``, where a parameter
change acts additively: a change ``d phi_k`` of the k-th body increment turns every
later attitude by ``R_{k+1/2} d phi_k``. Hence, to first order,

    z_j = chi0 + S_j (p_true - p0) + gyro random walk + R_j v_j,

with ``chi0`` the initial attitude error and ``v_j`` the star-tracker noise.

The columns ``S_j`` are built from the measured increments, which carry the gyro's random
walk. That noise is the residual's own, so the score ``S' W z`` at the truth would not be
zero on average (an errors-in-variables bias, largest in the channel-set difference where
the star-tracker noise cancels). The per-interval columns are therefore averaged over
`COLUMN_WINDOW_INTERVALS` star-tracker intervals (`smoothed_columns`): the noise they
share with any one interval's residual falls by that factor, while their running sums,
which the holds see, are unchanged. The columns then act as instruments: the estimate
solves ``S' W z = 0`` with ``S`` nearly free of the residual's noise (docs/validation.md,
"The structure test's excess").
"""

import json
from dataclasses import dataclass, fields

import numpy as np
from scipy.ndimage import uniform_filter1d
from scipy.spatial.transform import Rotation

from gyrocal.errors import InputError
from gyrocal.maneuvers.preprocess import ManeuverData
from gyrocal.model import channels as ch
from gyrocal.model import kinematics
from gyrocal.model.effects import ManeuverView
from gyrocal.model.spec import ModelSpec

__all__ = [
    "COLUMN_WINDOW_INTERVALS",
    "ON_GRID",
    "Linearization",
    "cumulative_at_st",
    "effect_derivatives",
    "effect_regressors",
    "gm_clock_steps",
    "linearize",
    "residuals",
    "smoothed_columns",
    "view",
    "walk_steps"
]

COLUMN_WINDOW_INTERVALS = 5
"""Star-tracker intervals the model's columns are averaged over: the ARW they share with one
interval's residual falls to 1/5 (at 1 Hz, the score test's mean at the truth fell from 5.98
to 1.47 against 1.38 with noise-free columns); around each change of rate a column's running
total is spread over half a window either side."""


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
    shared_walk: np.ndarray | None
    """(M, S, S, 3, 3) per-interval random-walk covariance of the sets per unit ARW^2, or None:
    then `random_walk` builds it from ``st_dt`` when asked (`_shared_walk`), as `linearize` and
    `from_arrays` leave it, since it is ``S^2`` times ``st_dt``'s size and mostly zeros."""
    body_error: np.ndarray
    """(M, S, 3) the same error in body axes (rad), for plots and diagnostics."""
    walk_var: np.ndarray | None = None
    """(M,) each star-tracker step's walk variance per unit ARW^2 (`walk_steps`); None: ``st_dt``."""
    walk_lag1: np.ndarray | None = None
    """(M,) the walk covariance of step j with step j - 1 per unit ARW^2 (the first: 0); None: none."""
    st_body_rate: np.ndarray | None = None
    """(M, 3) the body rate at the star-tracker times (rad/s, body axes, first set): what a timing
    jitter of the reference turns into attitude error (`covariance.build`); None: not kept."""
    gm_dt: np.ndarray | None = None
    """(M,) each step of the clock of the reference error's Gauss-Markov part (s): ``st_dt`` plus
    ``gm_clock_s_per_rad`` times the angle the body turns over the step (`gm_clock_steps`); None: ``st_dt``."""

    @property
    def gm_steps(self) -> np.ndarray:
        """The Gauss-Markov part's clock steps (s): `gm_dt`, or ``st_dt`` where it runs on time alone."""
        return self.st_dt if self.gm_dt is None else self.gm_dt

    def random_walk(self) -> np.ndarray:
        """`shared_walk`, built from the steps' walk variances where it was not given."""
        if self.shared_walk is not None:
            return self.shared_walk
        return _shared_walk(len(self.sets), self.st_dt if self.walk_var is None else self.walk_var)

    def walk_lag1_or_none(self):
        """`walk_lag1`, or None where consecutive steps share no walk (every sample on the gyro grid)."""
        return None if self.walk_lag1 is None or not np.any(self.walk_lag1) else self.walk_lag1

    def arrays(self, prefix: str) -> dict:
        """The fields as arrays named ``prefix + field`` (`numpy.savez`), less the random-walk
        covariance, which is built from ``st_dt`` when asked (`random_walk`)."""
        out = {prefix + f.name: getattr(self, f.name) for f in fields(self)
               if f.name not in _NOT_SAVED and getattr(self, f.name) is not None}
        out[prefix + "labels"] = np.asarray(json.dumps({"maneuver": self.maneuver, "sets": self.sets}))
        return out

    @classmethod
    def from_arrays(cls, arrays, prefix: str) -> "Linearization":
        """What `arrays` saved, the same to the bit as the linearisation that was saved."""
        labels = json.loads(str(arrays[prefix + "labels"]))
        sets = [tuple(s) for s in labels["sets"]]
        saved = {f.name: arrays[prefix + f.name] for f in fields(cls)
                 if f.name not in _NOT_SAVED and prefix + f.name in arrays}  # files before walk_var lack it
        return cls(labels["maneuver"], sets, shared_walk=None, **saved)


_NOT_SAVED = ("maneuver", "sets", "shared_walk")


def view(data: ManeuverData) -> ManeuverView:
    """What an effect sees of a maneuver: its data at nominal parameters, body rate from the
    in-loop set."""
    zeros = ch.ChannelParams.zeros(data.channels)
    first = data.sets[0]
    body = ch.solve_body(data.set_increments(first), zeros.subset(first), dt_s=data.dt)
    return ManeuverView(data, body / data.dt[:, None])


def effect_derivatives(effect, m: ManeuverView) -> tuple:
    """An effect's ``gyro`` and ``star_tracker`` derivatives on one maneuver; a missing
    extra column is refused (`InputError`), named with the columns the maneuver has."""
    try:
        return effect.gyro(m), effect.star_tracker(m)
    except KeyError as exc:
        raise InputError(f"effect {effect.name} needs {exc} in maneuver {m.id}, which has the "
                         f"extra gyro.csv columns {sorted(m.extras)}: add the column to gyro.csv, or leave "
                         f"{effect.name} out of this campaign's models") from exc


def effect_regressors(data: ManeuverData, spec: ModelSpec):
    """What the model's extra effects change, per unit parameter (SI), at nominal parameters.

    Returns (K, n_channels, E) changes of the raw channel increments and (M, 3, E)
    changes of the body-frame star-tracker error, E = the spec's extra parameters.
    """
    n_ch = len(data.channels)
    extras = spec.extras
    gyro = np.zeros((len(data.dt), n_ch, len(extras)))
    star = np.zeros((len(data.st_time), 3, len(extras)))
    if not extras:
        return gyro, star
    m = view(data)
    cache = {}
    for j, p in enumerate(extras):
        if p.effect not in cache:
            cache[p.effect] = effect_derivatives(spec.effect(p.effect), m)
        g, s = cache[p.effect]
        if p.name in g:
            column = np.asarray(g[p.name], dtype=float).reshape(len(data.dt), n_ch)
            if p.channel is None:
                gyro[:, :, j] = column
            else:
                gyro[:, p.channel, j] = column[:, p.channel]
        if p.name in s:
            star[:, :, j] = np.asarray(s[p.name], dtype=float).reshape(len(data.st_time), 3)
    return gyro, star


def _inverse_responses(positive: np.ndarray, scale: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """(K, 3, 3) inverses of the response matrices ``scale[k, :, None] * rows``: one per pattern of
    the channels' signs (at most eight), the same numbers as inverting each sample's matrix (the same
    LAPACK solve on the same matrix), gathered per sample."""
    pattern = positive @ (1 << np.arange(positive.shape[1]))
    _, first, which = np.unique(pattern, return_index=True, return_inverse=True)
    return np.linalg.inv(scale[first, :, None] * rows[None])[which.ravel()]


def _channel_derivatives(sub: ch.ChannelParams, u, phi, dt, wanted):
    """d(body increment)/d(parameter) of one channel set (eq. 3 inverted), (K, 3) each.

    Returns the channel-model terms keyed by ``(channel, name)`` for the keys in ``wanted`` (a
    symmetric ``sf``: the sum of the two branches' columns), the set's three bias
    columns (K, 3, 3) and the inverse response matrices (K, 3, 3).
    """
    positive = (u - np.outer(dt, sub.bias_rad_s)) > 0
    scale = 1.0 + np.where(positive, sub.sf_pos, sub.sf_neg)
    rows = ch.response_rows(sub)
    m_inv = _inverse_responses(positive, scale, rows)
    sensed = phi @ rows.T
    terms = {}
    for i, c in enumerate(sub.channels):
        w = -m_inv[:, :, i]
        if {(c.name, "sf_pos"), (c.name, "sf"), (c.name, "sf_neg")} & wanted:
            pos = w * (sensed[:, i] * positive[:, i])[:, None]
            neg = w * (sensed[:, i] * ~positive[:, i])[:, None]
            terms[c.name, "sf_pos"], terms[c.name, "sf_neg"] = pos, neg
            if (c.name, "sf") in wanted:
                terms[c.name, "sf"] = pos + neg  # symmetric: both branches
        for b in c.other_axes:
            if (c.name, f"mis_{b}") in wanted:
                terms[c.name, f"mis_{b}"] = w * (scale[:, i] * phi[:, ch.AXIS_INDEX[b]])[:, None]
    return terms, -m_inv * dt[:, None, None], m_inv


def linearize(data: ManeuverData, spec: ModelSpec, theta, bias_rad_s) -> Linearization:
    """Residuals and Jacobian of one maneuver about the parameters ``theta`` (SI, in the
    spec's column order) and this maneuver's channel biases; prior-only parameters
    (`identification`) get no column."""
    params = spec.channel_params(theta, bias_rad_s)
    extra_values = np.asarray(theta, dtype=float)[spec.extra]
    sets = data.sets
    names = [c.name for c in spec.channels]
    gyro_reg, star_reg = effect_regressors(data, spec)
    st_rot = Rotation.from_quat(data.st_quat)
    k, frac = data.st_interval()
    m = len(data.st_time)
    z = np.empty((m, len(sets), 3))
    body = np.empty((m, len(sets), 3))
    design = np.zeros((m, len(sets), 3, len(spec)))
    bias_design = np.zeros((m, len(sets), 3, len(names)))
    for s, channel_set in enumerate(sets):
        slots = [names.index(n) for n in channel_set]
        sub = params.subset(channel_set)
        regressors = gyro_reg[:, slots, :]
        u, phi, attitudes, at_st, e, st_columns = _set_error(data, channel_set, sub, regressors, extra_values,
                                                             star_reg, st_rot)
        core = [i for i, p in enumerate(spec.parameters[:spec.n_core]) if p.owner in channel_set]
        keys = [(spec.parameters[i].owner, spec.parameters[i].name) for i in core]
        terms, bias_columns, m_inv = _channel_derivatives(sub, u, phi, data.dt, set(keys))
        n = len(core)
        body_columns = np.empty((len(phi), 3, n + 3 + regressors.shape[2]))
        for j, key in enumerate(keys):
            body_columns[:, :, j] = terms[key]
        del terms
        body_columns[:, :, n:n + 3] = bias_columns
        body_columns[:, :, n + 3:] = -(m_inv @ regressors)
        mid = kinematics.compose(attitudes[:-1], Rotation.from_rotvec(0.5 * phi))
        inertial = mid.as_matrix() @ body_columns
        inertial = smoothed_columns(inertial, data.dt, data.st_time)
        at_st_jac = cumulative_at_st(inertial, k, frac)
        body[:, s] = e - star_reg @ extra_values
        z[:, s] = at_st.apply(e) - st_columns @ extra_values
        design[:, s][:, :, core] = at_st_jac[:, :, :n]
        bias_design[:, s][:, :, slots] = at_st_jac[:, :, n:n + 3]
        design[:, s, :, spec.extra] = at_st_jac[:, :, n + 3:] + st_columns
        if s == 0:
            st_matrix = at_st.as_matrix()
            st_rate = phi[k] / data.dt[k, None]
            start_first, at_st_first = attitudes[0], at_st
    design[..., ~spec.free] = 0.0
    st_dt = np.diff(np.concatenate([[data.gyro_time[0]], data.st_time]))
    walk_var, shared = walk_steps(data.gyro_time, data.st_time)
    gm_dt = (None if data.gm_clock_s_per_rad <= 0 else
             gm_clock_steps(st_dt, kinematics.net_turns(start_first, at_st_first), data.gm_clock_s_per_rad))
    return Linearization(data.id, sets, z, design, bias_design, st_matrix, st_dt, None, body, walk_var,
                         np.concatenate([[0.0], shared]), st_rate, gm_dt)


def gm_clock_steps(st_dt_s: np.ndarray, turns_rad: np.ndarray, clock_s_per_rad: float) -> np.ndarray:
    """(M,) the Gauss-Markov part's clock steps ``dt + kappa dtheta`` (s) between star-tracker samples, from
    the time steps and the turns over them (`kinematics.net_turns`), ``kappa`` in s/rad. An error that follows
    the pose (an optical tracker fitting its markers, seen by other cameras as the body turns) forgets with
    the angle turned as well as with time (docs/real-data.md)."""
    return st_dt_s + clock_s_per_rad * turns_rad


def _set_error(data: ManeuverData, channel_set, sub: ch.ChannelParams, regressors, extra_values, star_reg, st_rot):
    """One channel set's body increments ``u`` and ``phi`` (eq. 3 inverted), its propagated attitudes, those
    at the star-tracker samples, the error angles there (eq. 4) and the star tracker's effect columns:
    what `linearize` and `residuals` share, computed alike (the same bits)."""
    u = data.set_increments(channel_set) - regressors @ extra_values
    phi = ch.solve_body(u, sub, dt_s=data.dt)
    attitudes = kinematics.propagate(Rotation.from_quat(data.attitude0_quat), phi)
    at_st = kinematics.attitude_at(data.gyro_time, attitudes, phi, data.st_time)
    e = kinematics.error_angles_rad(at_st, st_rot)
    return u, phi, attitudes, at_st, e, at_st.as_matrix() @ star_reg


def residuals(data: ManeuverData, spec: ModelSpec, theta, bias_rad_s) -> np.ndarray:
    """`linearize`'s ``z`` alone, (M, S, 3), the same to the bit, without the Jacobian: what a trial
    step of the WLS needs (most of a linearisation's time is its derivative columns)."""
    params = spec.channel_params(theta, bias_rad_s)
    extra_values = np.asarray(theta, dtype=float)[spec.extra]
    names = [c.name for c in spec.channels]
    gyro_reg, star_reg = effect_regressors(data, spec)
    st_rot = Rotation.from_quat(data.st_quat)
    z = np.empty((len(data.st_time), len(data.sets), 3))
    for s, channel_set in enumerate(data.sets):
        regressors = gyro_reg[:, [names.index(n) for n in channel_set], :]
        *_, at_st, e, st_columns = _set_error(data, channel_set, params.subset(channel_set), regressors, extra_values,
                                             star_reg, st_rot)
        z[:, s] = at_st.apply(e) - st_columns @ extra_values
    return z


def smoothed_columns(per_interval: np.ndarray, dt_s: np.ndarray, st_time_s: np.ndarray) -> np.ndarray:
    """Per-gyro-interval columns (K, ...) averaged over `COLUMN_WINDOW_INTERVALS`
    star-tracker intervals (an odd number of gyro intervals, centred); the sum over the
    maneuver is kept, so each column's running total changes only within half a window."""
    if len(st_time_s) < 2:
        return per_interval
    st_interval_s = float(np.median(np.diff(st_time_s)))
    width = round(COLUMN_WINDOW_INTERVALS * st_interval_s / float(np.median(dt_s)))
    width += 1 - width % 2
    if width <= 1:
        return per_interval
    return uniform_filter1d(per_interval, size=width, axis=0, mode="reflect")


def cumulative_at_st(per_interval: np.ndarray, k: np.ndarray, frac: np.ndarray) -> np.ndarray:
    """Running sum of per-gyro-interval terms, evaluated at the star-tracker samples
    (a sample inside interval k has the sum of the intervals before it plus its share)."""
    cumulative = np.empty((len(per_interval) + 1,) + per_interval.shape[1:])
    cumulative[0] = 0.0
    np.cumsum(per_interval, axis=0, out=cumulative[1:])
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


ON_GRID = 1e-9
"""A star-tracker sample closer than this share of a gyro interval to a gyro sample is on it."""


def walk_steps(gyro_time: np.ndarray, st_time: np.ndarray) -> tuple:
    """The gyro walk of the differenced error per unit ARW^2 (s): each star-tracker step's variance and
    the covariance of consecutive steps. A sample a fraction f into gyro interval k sees that interval's
    noise as ``f n_k`` (`kinematics.attitude_at` interpolates the increment), so its walk has variance
    ``t_k - t_0 + f^2 dt_k``, not ``t - t_0``: step j has ``st_dt_j - dt (f_{j-1} (1 - f_{j-1}) +
    f_j (1 - f_j))`` and shares ``dt_k f_j (1 - f_j)`` with step j+1. On the gyro grid (f = 1) the steps
    are ``st_dt`` and independent, as `_shared_walk` has them; between gyro samples the short-term walk
    is smaller, and a model that counts ``st_dt`` puts the ARW low (docs/validation.md, "The fitted ARW")."""
    dt = np.diff(gyro_time)
    k = np.clip(np.searchsorted(gyro_time, st_time, side="left") - 1, 0, len(dt) - 1)
    frac = (st_time - gyro_time[k]) / dt[k]
    inside = dt[k] * frac * (1.0 - frac)
    inside[frac * (1.0 - frac) < ON_GRID] = 0.0  # on a gyro sample but for rounding: st_dt, to the bit
    st_dt = np.diff(np.concatenate([[gyro_time[0]], st_time]))
    return st_dt - inside - np.concatenate([[0.0], inside[:-1]]), inside[:-1]
