"""What both sensors saw during one maneuver, and the regression of the gyro's rotation on the
star tracker's that every physics check of the input starts from."""

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.spatial.transform import Rotation

from gyrocal.inference.errormodel import cumulative_at_st
from gyrocal.inference.fit.identification import DETECTION_SD
from gyrocal.maneuvers import preprocess
from gyrocal.model import channels as ch
from gyrocal.model.spec import baseline

__all__ = [
    "CHECK_BLOCK_S",
    "FIT_COLUMNS",
    "OUTLIER_REACH",
    "SIGNAL_TO_NOISE_MIN",
    "Response",
    "RotationFit",
    "Sensed",
    "blocked_sums",
    "consistent",
    "consistent_any",
    "fit_rotation",
    "gyro_at_st",
    "interval_rotations",
    "neighbour_residual",
    "nominal_body_increments",
    "physical_limits",
    "reference_noise_rad",
    "response",
    "sense"
]

OUTLIER_REACH = 3
"""The outlier screen compares a sample with the interpolations of up to this many pairs of neighbours."""



@dataclass
class RotationFit:
    """The gyro rotation per interval regressed on the star tracker's about the maneuver axis."""

    axis: int
    """The axis the star tracker rotates about most."""
    net_rad: float
    """Net star-tracker rotation about the labelled axis."""
    excursion_rad: np.ndarray
    """(3,) range of the star tracker's cumulative rotation about each axis (its noise does not
    accumulate: the sum of the interval rotations telescopes to the attitude change)."""
    response: np.ndarray
    """(3,) gyro rotation per unit star-tracker rotation about the labelled axis."""
    response_sd: np.ndarray


def interval_rotations(st_quat) -> np.ndarray:
    """(M-1, 3) body-frame rotation vectors of the star tracker between consecutive samples."""
    r = Rotation.from_quat(st_quat)
    return (r[:-1].inv() * r[1:]).as_rotvec()


def gyro_at_st(data, increments) -> np.ndarray:
    """(M-1, 3) summed body increments between star-tracker samples."""
    k, frac = data.st_interval()
    cumulative = cumulative_at_st(increments, k, frac)
    return np.diff(cumulative, axis=0)


def nominal_body_increments(data, raw, set_index: int = 0) -> np.ndarray:
    """Body increments of one channel set (the in-loop one by default) from raw channel increments
    (nominal model), so a reinterpretation of the raw columns can be tried."""
    channel_set = data.sets[set_index]
    index = {c.name: i for i, c in enumerate(data.channels)}
    zeros = ch.ChannelParams.zeros(data.channels)
    return ch.solve_body(raw[:, [index[n] for n in channel_set]], zeros.subset(channel_set))


@dataclass
class Sensed:
    """What both sensors saw during one maneuver, computed once for every check."""

    data: object
    """The maneuver (`preprocess.ManeuverData`)."""
    body: np.ndarray
    """(K, 3) body increments of the channel set at nominal parameters (rad)."""
    d_gyro: np.ndarray
    """(M-1, 3) those increments summed between star-tracker samples (rad)."""
    d_st: np.ndarray
    """(M-1, 3) the star tracker's rotation between its samples, body axes (rad)."""
    dt: np.ndarray
    """(M-1,) star-tracker sample intervals (s)."""
    set_index: int = 0
    """Which channel set of ``data.sets`` the gyro side is (0: the in-loop one)."""

    @property
    def where(self) -> str:
        """The maneuver, and the channel set where it is not the in-loop one, as findings name them."""
        m = self.data
        return f"maneuver {m.id} ({m.turn})" + (f", channels {'+'.join(m.sets[self.set_index])}" if self.set_index else "")

    @cached_property
    def d_gyro_turned(self) -> np.ndarray:
        """(M-1, 3) the gyro's rotation between star-tracker samples with its increments composed, as
        the reference's is (rad, body axes at the earlier sample): `d_gyro` less its coning error,
        which grows as the square of the turn per interval where the axis moves (a fast tumble: 7-13 %
        of the turn at 0.1 s on BROAD's hand-held trials). `d_gyro` stays linear in the increments, for
        the reinterpretations of the raw columns (a unit, a sign, a cumulative angle) to be tried on."""
        zeros = ch.ChannelParams.zeros(self.data.channels)
        _, _, at_st = preprocess.propagate_set(self.data, self.data.sets[self.set_index], zeros)
        return (at_st[:-1].inv() * at_st[1:]).as_rotvec()

    @cached_property
    def error(self) -> np.ndarray:
        """(M, 3) each sample's error angle between the sensors (eq. 4, nominal parameters, rad)."""
        zeros = ch.ChannelParams.zeros(self.data.channels)
        return preprocess.error_angles(self.data, self.data.sets[0], zeros)

    @cached_property
    def departures(self) -> np.ndarray:
        """(M, 3) `error` less the interpolation of its neighbours (`neighbour_residual`): the
        reference's noise estimate and the outlier screen both start from it."""
        return neighbour_residual(self.error)


def sense(data, set_index: int = 0) -> Sensed:
    """Both sensors' rotations of one maneuver, the gyros' through channel set ``set_index``, for
    every check of it."""
    body = nominal_body_increments(data, data.increments, set_index)
    return Sensed(data, body, gyro_at_st(data, body), interval_rotations(data.st_quat), np.diff(data.st_time),
                  set_index)


def fit_rotation(d_gyro, d_st, dt, axis: int, bias=True) -> RotationFit:
    """Least squares of the gyro's interval rotations on the star tracker's about all three axes
    and (with ``bias``) a constant rate. The response to rotation about ``axis`` is 1 + scale
    error on that axis and the misalignments across; the other axes' columns take up any motion
    about them (a hand-held trial turns about more than one axis). With no more intervals than
    columns nothing is left to measure the noise by, and the response's sd is infinite."""
    excursion = np.ptp(np.cumsum(d_st, axis=0), axis=0)
    x = np.column_stack([d_st, dt] if bias else [d_st])
    coef, *_ = np.linalg.lstsq(x, d_gyro, rcond=None)
    resid = d_gyro - x @ coef
    sigma = 1.4826 * np.median(np.abs(resid - np.median(resid, axis=0)), axis=0) + 1e-15
    if len(x) <= x.shape[1]:
        sigma = np.full(3, np.inf)  # no residual to measure the noise by: the response is not determined
    info = np.linalg.pinv(x.T @ x)[axis, axis]
    return RotationFit(int(np.argmax(excursion)), float(d_st[:, axis].sum()), excursion, coef[axis],
                       sigma * np.sqrt(info))


FIT_COLUMNS = 4
"""The rotation fits' columns: the reference's rotation about three axes and a constant rate. With no
more blocks than these, no residual is left to measure the noise by."""

CHECK_BLOCK_S = 1.0
"""The rotation checks compare the sensors over blocks of samples at least this long: over a
fast reference's single interval, its noise and any sub-sample timing would bias the slope."""


MAX_TURN_BETWEEN_REFERENCE_DEG = 90.0
"""The checks compare rotations between reference samples, which are ambiguous beyond half a
turn; a clipped or mis-scaled gyro understates the turn, so they ask for half that."""


def comparable(d_gyro) -> np.ndarray:
    """Mask of the reference intervals whose rotation the gyro's can be held against: where the gyro
    turns at most `MAX_TURN_BETWEEN_REFERENCE_DEG` (beyond, the reference's own rotation may be wrapped
    by whole turns, as across a few samples the motion capture lost during a fast turn). ``d_gyro``:
    the summed increments (`Sensed.d_gyro`), whose length is the turn, never wrapped."""
    return np.rad2deg(np.linalg.norm(d_gyro, axis=1)) <= MAX_TURN_BETWEEN_REFERENCE_DEG


def _kept(keep, *series):
    """``series`` on the intervals ``keep`` marks, unless it marks none (then all: the caller's
    refusal names the sparse reference)."""
    keep = np.asarray(keep, dtype=bool)
    return series if not keep.any() or keep.all() else tuple(x[keep] for x in series)


def blocked_sums(dt, *series):
    """Sums of consecutive intervals over blocks of at least `CHECK_BLOCK_S` (the dt first); one block
    of them all where they span less (a reading under which the gyro turns too far to compare in
    most intervals can leave a few short ones)."""
    size = max(1, min(round(CHECK_BLOCK_S / float(np.median(dt))), len(dt)))
    n = len(dt) // size * size
    return [x[:n].reshape(n // size, size, *x.shape[1:]).sum(axis=1) for x in (dt, *series)]


def consistent(d_gyro, d_st, dt, axis, sf_bound, mis_bound) -> bool:
    """Whether the gyro's rotation matches the star tracker's within the physical bounds, with
    a bias fitted or (where a rotation at one steady rate leaves it confounded with the
    scale) without; over blocks of `CHECK_BLOCK_S`, the intervals the gyro turns too far in to compare
    (`comparable`) left out."""
    dt, d_gyro, d_st = blocked_sums(*_kept(comparable(d_gyro), dt, d_gyro, d_st))
    return any(_within(fit_rotation(d_gyro, d_st, dt, axis, bias), axis, sf_bound, mis_bound) for bias in (True, False))


def _within(fit: RotationFit, axis: int, sf_bound, mis_bound) -> bool:
    others = [b for b in range(3) if b != axis]
    scale_ok = abs(fit.response[axis] - 1.0) <= sf_bound + DETECTION_SD * fit.response_sd[axis]
    cross_ok = all(abs(fit.response[b]) <= mis_bound + DETECTION_SD * fit.response_sd[b] for b in others)
    determined = DETECTION_SD * fit.response_sd[axis] <= sf_bound
    return bool(scale_ok and cross_ok and determined and fit.axis == axis)


@dataclass
class Response:
    """The gyros' rotation against the reference's over one maneuver, as a 3x3 response: least
    squares of the gyro's interval rotations on the reference's (and a constant rate), in the
    principal directions of the reference's motion (an eigen-axis slew spans one, a tumble up to
    three). ``matrix[:, k]``: gyro rotation per unit reference rotation along ``directions[:, k]``,
    that direction itself plus the scale errors and misalignments it meets."""

    directions: np.ndarray
    """(3, 3) unit vectors in body axes, columns, the most-turned first."""
    matrix: np.ndarray
    sd: np.ndarray
    determined: np.ndarray
    """(3,) directions along which the motion determines the response within the physical scale
    bound (`DETECTION_SD` sds) and the reference's motion stands `SIGNAL_TO_NOISE_MIN` clear of its noise."""
    strong: np.ndarray
    """(3,) directions along which the reference's motion stands `SIGNAL_TO_NOISE_MIN` clear of the noise
    the check is given, determined or not (that noise is the two sensors' difference, which a gross gyro
    fault inflates too: `physics.path_ratio` names such faults)."""
    sparse: bool = False
    """Every interval was kept though some turn too far to compare, or too few blocks were left without
    them: only a determined direction counts as evidence then."""
    short: bool = False
    """No more blocks than the fit's columns (three directions, and the rate with a bias): nothing is
    left to measure the noise by, and no direction is judged."""

    def within(self, sf_bound, mis_bound, need_determined=False) -> bool:
        """Along every determined direction u, and every direction the reference turns clearly along,
        each body axis b of the response within what eq. 3 allows, ``u_b`` give or take ``sf_bound |u_b| +
        mis_bound sum_(c != b) |u_c|``, and `DETECTION_SD` standard errors: a gyro that reads 57 times the
        reference fails where its scatter is narrow enough to say so. A motion too weak to determine any
        direction gives no evidence against the gyros (the no-rotation check stands for a window on a
        hold), unless ``need_determined`` (a reinterpretation of the data must show it fits) or the
        response had to keep intervals it could not compare (`sparse`)."""
        if (need_determined or self.sparse) and not self.determined.any():
            return False
        for k in np.flatnonzero(self.determined | self.strong):
            u = self.directions[:, k]
            allowed = sf_bound * np.abs(u) + mis_bound * (np.abs(u).sum() - np.abs(u))
            if np.any(np.abs(self.matrix[:, k] - u) > allowed + DETECTION_SD * self.sd[:, k]):
                return False
        return True


SIGNAL_TO_NOISE_MIN = 100.0
"""A direction of the motion is judged only where the reference's rotation along it, per block, has
this many times the variance of its noise: below, the noise biases the slope (errors in variables)
by more than a percent, beyond the scale bound of a DTG."""


def response(d_gyro, d_st, dt, sf_bound, bias=True, noise_rad=0.0, keep=None) -> Response:
    """The 3x3 `Response` of the gyros to the reference over blocks of `CHECK_BLOCK_S`, for any motion;
    ``noise_rad``: one reference sample's noise (`reference_noise_rad`). The intervals the gyro turns too
    far in to compare are left out, unless all are: ``keep``, or `comparable` of ``d_gyro`` (pass the
    mask of the summed increments where ``d_gyro`` is composed, whose length wraps)."""
    keep = np.asarray(comparable(d_gyro) if keep is None else keep, dtype=bool)
    blocked = blocked_sums(*_kept(keep, dt, d_gyro, d_st))
    sparse = not keep.all()
    if len(blocked[0]) < 4:  # too few blocks left to fit a 3x3 response and a rate: keep every interval
        blocked = blocked_sums(dt, d_gyro, d_st)
    elif keep.any():
        sparse = False
    dt, d_gyro, d_st = blocked
    if len(dt) <= FIT_COLUMNS - (not bias):  # no residual left to measure the noise by: no direction judged
        none = np.zeros(3, dtype=bool)
        return Response(np.eye(3), np.eye(3), np.full((3, 3), np.inf), none, none, sparse, short=True)
    _, _, vt = np.linalg.svd(d_st, full_matrices=False)
    largest = np.argmax(np.abs(vt), axis=1)
    directions = (vt * np.sign(vt[np.arange(len(vt)), largest])[:, None]).T  # each its largest component positive
    z = d_st @ directions
    x = np.column_stack([z, dt] if bias else [z])
    gram = x.T @ x
    coef, *_ = np.linalg.lstsq(x, d_gyro, rcond=None)
    resid = d_gyro - x @ coef
    noise = 2 * noise_rad**2  # a block's rotation telescopes: the noise of its two ends
    sigma = 1.4826 * np.median(np.abs(resid - np.median(resid, axis=0)), axis=0) + 1e-15
    sd = np.outer(sigma, np.sqrt(np.diag(np.linalg.pinv(gram))[:3]))
    along = np.sqrt(np.einsum("bk,bk->k", directions**2, sd**2))
    signal = np.diag(gram)[:3] / len(dt) / np.maximum(noise, 1e-30) - 1.0
    strong = signal >= SIGNAL_TO_NOISE_MIN
    return Response(directions, coef[:3].T, sd, (DETECTION_SD * along <= sf_bound) & strong, strong, sparse)


def consistent_any(d_gyro, d_st, dt, sf_bound, mis_bound, noise_rad=0.0, need_determined=False, keep=None) -> bool:
    """`consistent` for any motion (free, several axes at once): the 3x3 `Response`, with a bias
    fitted or without, within the physical bounds on every axis the motion determines (``keep``: as
    `response`'s)."""
    return any(response(d_gyro, d_st, dt, sf_bound, bias, noise_rad, keep).within(sf_bound, mis_bound, need_determined)
               for bias in (True, False))


def physical_limits(channels, sensor_class=None):
    """Largest physical scale error and misalignment (SI), and the scale factor's prior sd, of the
    campaign's sensor class (`gyrocal.model.sensorclass`; None: a DTG's, as the baseline effects
    declare them)."""
    spec = baseline(channels).with_sensor_class(sensor_class)
    bounds = {p.name: b for p, b in zip(spec.parameters, spec.bound_si)}
    sds = {p.name: s for p, s in zip(spec.parameters, spec.prior_sd_si)}
    mis = max(v for k, v in bounds.items() if k.startswith("mis_"))
    return bounds["sf_pos"], mis, sds["sf_pos"]


def reference_noise_rad(sensed: Sensed) -> float:
    """The noise of one reference sample as the data show it (rad, a robust sd over the three
    axes): the smaller of two upper bounds. One is the spread of the sensors' error angles
    about the interpolation of their neighbours (`neighbour_residual`), where a bias, a scale
    error and a steady rate cancel; it holds at any sample interval, but a gyro fault (a unit
    slip) inflates it. The other is the spread of the reference's own interval rotations, which
    no gyro fault touches; it is the noise only where the reference barely turns between
    samples, and otherwise the motion per interval, which grows with the interval (thinned to
    1 s, a hand-held reference turns tens of degrees per interval) though the noise does not."""
    d_st = sensed.d_st
    between = 1.4826 * np.median(np.abs(sensed.departures[1:-1]))
    own = 1.4826 * np.median(np.abs(d_st - np.median(d_st, axis=0))) / np.sqrt(2)
    return float(min(between, own) + 1e-12)




def neighbour_residual(x, reach=OUTLIER_REACH) -> np.ndarray:
    """Each row of ``x`` (M, p) minus the median of its neighbours' linear interpolations
    ``(x[k-j] + x[k+j]) / 2``, j = 1..reach: zero on any straight line, and a kink leaves only
    its change of slope. A single outlier moves one interpolation of its neighbours, which the
    median ignores. The first and last rows have no pair: they are returned as zero."""
    m = len(x)
    padded = np.concatenate([np.full((reach,) + x.shape[1:], np.nan), x, np.full((reach,) + x.shape[1:], np.nan)])
    pairs = np.stack([0.5 * (padded[reach - j:reach - j + m] + padded[reach + j:reach + j + m])
                      for j in range(1, reach + 1)])
    resid = np.zeros_like(x)
    resid[1:-1] = x[1:-1] - np.nanmedian(pairs[:, 1:-1], axis=0)
    return resid
