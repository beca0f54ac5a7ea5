"""Deterministic point estimates: the paper's hold-averaged method and full-trajectory WLS."""

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.optimize import least_squares, minimize
from scipy.spatial.transform import Rotation

from . import channels as ch
from . import errormodel, kinematics, noise
from .likelihood import campaign_stats
from .preprocess import ManeuverData, body_increments
from .units import AXES, AXIS_INDEX

HOLD_RATE_FRACTION = 0.05
"""A sample belongs to a hold while the maneuver-axis rate is below this share of its peak."""


def variances(log_sigma) -> dict:
    """Noise variances from ``log [sigma_cross_rad, sigma_about_rad, arw_rad_sqrt_s]``."""
    s = np.exp(2.0 * np.asarray(log_sigma, dtype=float))
    return {"cross": s[0], "about": s[1], "walk": s[2]}


def hold_windows(data: ManeuverData, channel_set=None):
    """Star-tracker masks of the inertial holds before and after the rotation."""
    channel_set = channel_set or data.sets[0]
    inc = body_increments(data, channel_set, ch.ChannelParams.zeros(data.channels))
    rate = np.abs(inc[:, AXIS_INDEX[data.axis]] / data.dt)
    moving = np.flatnonzero(rate > HOLD_RATE_FRACTION * rate.max())
    t_first, t_last = data.gyro_time[moving[0]], data.gyro_time[moving[-1] + 1]
    return data.st_time < t_first, data.st_time > t_last


def classic(data: ManeuverData) -> pd.DataFrame:
    """The paper's method: the error held after the rotation, per unit rotation.

    For the channel on the rotated axis a, ``sf = -(mean error after - mean error
    before) / angle`` (the sign branch of the maneuver's direction). The channels on
    the other axes see the rotation through their misalignment toward a; their error
    turns with the body during the rotation, so instead of dividing by the angle we
    divide by the kinematic matrix of the actual trajectory, which is the angle for
    the scale factor and reduces to it for small rotations. The hold averages are
    differenced in the inertial frame, where the initial attitude offset stays put.
    """
    before, after = hold_windows(data)
    a = AXIS_INDEX[data.axis]
    others = [b for b in range(3) if b != a]
    zeros = ch.ChannelParams.zeros(data.channels)
    st_rot = Rotation.from_quat(data.st_quat)
    end = np.flatnonzero(after)[-1]
    rows = []
    for s, channel_set in enumerate(data.sets):
        inc = body_increments(data, channel_set, zeros)
        attitudes = kinematics.propagate(Rotation.from_quat(data.attitude0_quat), inc)
        at_st = kinematics.attitude_at(data.gyro_time, attitudes, inc, data.st_time)
        inertial_err = at_st.apply(kinematics.error_angles_rad(at_st, st_rot))
        mid = kinematics.compose(attitudes[:-1], Rotation.from_rotvec(0.5 * inc))
        unit = np.zeros((len(inc), 3, 3))
        unit[:, [a] + others, [0, 1, 2]] = inc[:, a:a + 1]
        inertial = np.einsum("kij,kjp->kip", mid.as_matrix(), unit)
        design = errormodel.cumulative_at_st(inertial, *data.st_interval())
        to_body = at_st[end].inv().as_matrix()
        kin = -to_body @ (design[after].mean(axis=0) - design[before].mean(axis=0))
        delta = to_body @ (inertial_err[after].mean(axis=0) - inertial_err[before].mean(axis=0))
        solution = np.linalg.solve(kin, delta)
        angle = inc[:, a].sum()
        branch = "sf_pos" if angle > 0 else "sf_neg"
        rows.append({"maneuver": data.id, "set": s, "channel": channel_set[a], "parameter": branch,
                     "value": solution[0], "angle_rad": angle})
        for j, b in enumerate(others):
            rows.append({"maneuver": data.id, "set": s, "channel": channel_set[b],
                         "parameter": f"mis_{AXES[a]}", "value": solution[1 + j], "angle_rad": angle})
    return pd.DataFrame(rows)


def classic_campaign(maneuvers) -> pd.DataFrame:
    """`classic` over every maneuver; a parameter seen twice is averaged."""
    table = pd.concat([classic(d) for d in maneuvers], ignore_index=True)
    return (table.groupby(["channel", "parameter"], sort=False)
            .agg(value=("value", "mean"), n=("value", "size")).reset_index())


@dataclass
class PointEstimate:
    """Full-trajectory WLS solution and its Jacobian covariance, all SI."""

    channels: tuple
    theta: np.ndarray
    cov: np.ndarray
    biases: np.ndarray
    """(n_maneuvers, n_channels) rad/s."""
    chi0: np.ndarray
    log_sigma: np.ndarray
    """log [sigma_cross_rad, sigma_about_rad, arw_rad_sqrt_s] used for the weights."""
    cost: float
    nfev: int
    message: str
    extras: list = field(default_factory=list)
    """`effects.ExtraParameter` of the columns after the baseline's 24."""
    correlation_time_s: float = 0.0
    """Correlation time of the star-tracker noise (0: white)."""

    @property
    def n_base(self) -> int:
        return ch.N_PARAMS_PER_CHANNEL * len(self.channels)

    def params(self, m: int) -> ch.ChannelParams:
        return ch.ChannelParams.from_vector(self.channels, self.theta[:self.n_base], self.biases[m])

    def linearize(self, maneuvers, m: int):
        return errormodel.linearize(maneuvers[m], self.params(m), self.extras, self.theta[self.n_base:])


def _unpack(x, n_par, n_man, n_ch):
    theta = x[:n_par]
    nuis = x[n_par:].reshape(n_man, 3 + n_ch)
    return theta, nuis[:, :3], nuis[:, 3:]


def wls(maneuvers, channels, boresight, log_sigma, theta0=None, biases0=None, chi00=None, extras=(),
        correlation_time_s=0.0):
    """Weighted least squares over every maneuver with `scipy.optimize.least_squares`.

    Unknowns: the channel parameters of all channels, and per maneuver the initial
    attitude error and the bias of each channel. The exact nonlinear model is
    re-propagated at every step; weights come from the banded noise covariance
    (star tracker across and about its boresight, gyro random walk).
    """
    n_ch, n_man = len(channels), len(maneuvers)
    n_base = ch.N_PARAMS_PER_CHANNEL * n_ch
    n_par = n_base + len(extras)
    theta0 = np.zeros(n_par) if theta0 is None else theta0
    biases0 = np.zeros((n_man, n_ch)) if biases0 is None else biases0
    chi00 = np.zeros((n_man, 3)) if chi00 is None else chi00
    x0 = np.concatenate([theta0, np.column_stack([chi00, biases0]).ravel()])
    var = variances(log_sigma)
    def lin_at(m, theta, biases):
        return errormodel.linearize(maneuvers[m], ch.ChannelParams.from_vector(channels, theta[:n_base], biases),
                                    extras, theta[n_base:])

    first = [lin_at(m, theta0, biases0[m]) for m in range(n_man)]
    noises = [noise.build(lin, boresight, correlation_time_s) for lin in first]
    chols = [nz.factor(var) for nz in noises]
    cache = {}

    def evaluate(x):
        key = x.tobytes()
        if key in cache:
            return cache[key]
        theta, chi0, biases = _unpack(x, n_par, n_man, n_ch)
        res, jac_rows = [], []
        for m, d in enumerate(maneuvers):
            lin = lin_at(m, theta, biases[m])
            nz = noises[m]
            r = noise.difference(lin.z - chi0[m]).reshape(-1)
            nuis = noise.difference(noise.nuisance_design(lin)).reshape(nz.n, -1)
            j_theta = -noise.difference(lin.design).reshape(nz.n, -1)
            res.append(nz.whiten(chols[m], r))
            block = np.zeros((nz.n, len(x)))
            block[:, :n_par] = nz.whiten(chols[m], j_theta)
            cols = slice(n_par + m * (3 + n_ch), n_par + (m + 1) * (3 + n_ch))
            block[:, cols] = -nz.whiten(chols[m], nuis)
            jac_rows.append(block)
        cache.clear()
        cache[key] = (np.concatenate(res), np.vstack(jac_rows))
        return cache[key]

    result = least_squares(lambda x: evaluate(x)[0], x0, jac=lambda x: evaluate(x)[1],
                           method="trf", x_scale="jac", ftol=1e-10, xtol=1e-8, gtol=1e-10, max_nfev=30)
    jac = evaluate(result.x)[1]
    cov_full = np.linalg.inv(jac.T @ jac)
    theta, chi0, biases = _unpack(result.x, n_par, n_man, n_ch)
    return PointEstimate(tuple(channels), theta, cov_full[:n_par, :n_par], biases, chi0,
                         np.asarray(log_sigma, dtype=float), float(2 * result.cost), int(result.nfev),
                         str(result.message), list(extras), float(correlation_time_s))


def linearize_all(maneuvers, estimate: PointEstimate, boresight):
    """Linearisations and noise structures of every maneuver about a point estimate."""
    lins = [estimate.linearize(maneuvers, m) for m in range(len(maneuvers))]
    return lins, [noise.build(lin, boresight, estimate.correlation_time_s) for lin in lins]


def correlation_time(lins) -> float:
    """Correlation time of the star-tracker noise from the residuals (s; 0 if white).

    For first-order Gauss-Markov noise with coefficient phi per sample, the first
    differences have lag-1 autocorrelation -(1 - phi)/2, and -1/2 when white; the slow
    signal and the gyro walk barely touch the differences.
    """
    num = den = 0.0
    steps = []
    for lin in lins:
        x = np.diff(lin.body_error[:, 0, :], axis=0)
        num += float(np.sum(x[1:] * x[:-1]))
        den += float(np.sum(x * x))
        steps.append(np.median(lin.st_dt[1:]))
    phi = 1.0 + 2.0 * num / den
    if phi <= 0.05:
        return 0.0
    return float(-np.median(steps) / np.log(min(phi, 0.999)))


def _profile_reml(noises, ratios):
    """REML of the noise with the cross-boresight variance profiled out in closed form.

    ``ratios`` are ``log(sigma_about / sigma_cross)`` and ``log(arw / sigma_cross)``
    (arw per sqrt(s)); the covariance is ``sigma_cross^2`` times one built from them.
    Returns the negative log-likelihood (up to a constant) and ``log sigma_cross``.
    """
    stats = campaign_stats(noises, variances([0.0, ratios[0], ratios[1]]))
    factor = np.linalg.cholesky(stats.A)
    explained = np.linalg.solve(factor, stats.b)
    n = stats.n - len(stats.b)
    scale = (stats.c - explained @ explained) / n
    negative = 0.5 * (n * np.log(scale) + stats.logdet + 2 * np.sum(np.log(np.diag(factor))))
    return negative, 0.5 * np.log(scale)


def estimate_noise(noises, log_sigma0) -> np.ndarray:
    """Type-II maximum likelihood (REML) of ``log [sigma_cross, sigma_about, arw]``.

    The channel parameters and the nuisance are integrated out under flat priors.
    """
    log_sigma0 = np.asarray(log_sigma0, dtype=float)
    start = log_sigma0[1:] - log_sigma0[0]
    opt = minimize(lambda r: _profile_reml(noises, r)[0], start, method="Nelder-Mead",
                   options={"xatol": 1e-3, "fatol": 1e-3})
    log_cross = _profile_reml(noises, opt.x)[1]
    return np.array([log_cross, log_cross + opt.x[0], log_cross + opt.x[1]])


def classic_vector(table: pd.DataFrame, channels) -> np.ndarray:
    """The `classic_campaign` table as a parameter vector; parameters it lacks are zero."""
    labels = ch.parameter_labels(channels)
    theta = np.zeros(len(labels))
    for row in table.itertuples():
        theta[labels.index(f"{row.channel}.{row.parameter}")] = row.value
    return theta


def point_estimate(maneuvers, channels, boresight, log_sigma0, estimate_scales=True, extras=(),
                   correlated=False) -> PointEstimate:
    """Classic estimate, REML noise scales about it, then WLS from it at those scales.

    The classic estimate is within a few tens of ppm of the optimum, so the model is
    linear enough about it for the noise scales; the WLS then needs a few steps.
    """
    theta0 = np.concatenate([classic_vector(classic_campaign(maneuvers), channels), np.zeros(len(extras))])
    log_sigma = np.asarray(log_sigma0, dtype=float)
    start = PointEstimate(tuple(channels), theta0, None, np.zeros((len(maneuvers), len(channels))),
                          None, log_sigma, np.nan, 0, "classic", list(extras))
    tau = 0.0
    if estimate_scales or correlated:
        lins, noises = linearize_all(maneuvers, start, boresight)
        if correlated:
            start.correlation_time_s = tau = correlation_time(lins)
            noises = [noise.build(lin, boresight, tau) for lin in lins]
        if estimate_scales:
            log_sigma = estimate_noise(noises, log_sigma)
    return wls(maneuvers, channels, boresight, log_sigma, theta0, extras=extras, correlation_time_s=tau)
