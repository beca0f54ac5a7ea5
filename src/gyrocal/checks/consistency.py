"""Physical consistency of a campaign, before any fit: do the gyros see what the star tracker sees?

Format checks (`telemetry`) cannot tell increments in degrees from increments in radians,
or a scalar-first quaternion from a scalar-last one. Here each maneuver's gyro rotation,
summed between star-tracker samples, is compared with the star tracker's own rotation
over the same interval. A fault shows as a factor (57.3: degrees; the sample rate: rates),
an axis or direction other than the label, a gap, or a clock offset. Each finding says
what was found and its likely cause. The thresholds come from the physical bounds the
effects declare and from the noise measured in the data themselves, not from one file.

The star-tracker outlier screen lives here too: a sample far off its neighbours, beyond
what the data's own noise allows, is listed and kept out of the fit.
"""

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
from scipy.ndimage import median_filter
from scipy.spatial.transform import Rotation
from scipy.special import chdtr, chdtri, gammaincinv

from gyrocal.inference import classic, preprocess
from gyrocal.inference.errormodel import cumulative_at_st
from gyrocal.inference.identification import DETECTION_SD
from gyrocal.io.telemetry import UNIT_NORM_TOL, Campaign, TelemetryError, read_campaign
from gyrocal.io.telemetry import summary as format_summary
from gyrocal.model import channels as ch
from gyrocal.model.spec import baseline
from gyrocal.model.units import AXES, AXIS_INDEX, rad_to_arcsec

GAP_FACTOR = 3.0
"""A time step longer than this many median steps is a gap."""

OUTLIER_FALSE_ALARMS = 0.01
"""Expected star-tracker samples wrongly called outliers per campaign, under the data's own noise."""

OUTLIER_REACH = 3
"""The outlier screen compares a sample with the interpolations of up to this many pairs of neighbours."""

OUTLIER_MAX_RUN = 3
"""An outlier stands alone: a wrong star identification or a reference glitch lasts a sample or
a few. Longer runs beyond the noise are excursions (`EXCURSION_MAX_S`) or structure for the
model, which stays in the fit."""

EXCURSION_MAX_S = 5.0
"""A reference excursion leaves the trend of the error between the sensors with a jump and comes
back within this time: a motion-capture marker swap, or a star tracker's filter holding a wrong
attitude. The jump must be one the motion does not explain (`outlier_distances` takes out what
scale errors, misalignments, a time offset and a nonlinearity would leave), since a scale error
over a there-and-back turn also comes back; an unexplained error of the gyros integrates: it
can step, but it cannot come back."""

EXCURSION_TREND_S = 3 * EXCURSION_MAX_S
"""The error's trend is its running median over this window: an excursion shorter than half of it
does not move the median."""

EXCURSION_EDGE_CUT = float(2 * gammaincinv(1.5, 0.99))
"""An excursion extends on either side while its samples stay off the trend beyond this (the
chi-square 99 % point on three degrees of freedom), so that its edges leave the fit with it."""

MAX_CLOCK_SEARCH_S = 60.0
"""The clock-offset search spans at most this far either way."""

CLOCK_SEARCH_POINTS = 400
"""Shifts of the clock-offset search's coarse pass; a fine pass at a quarter of a star-tracker
step follows about its best (the misfit varies smoothly with the shift)."""

ALTERNATIVES = (
    (180.0 / np.pi, "increments in degrees rather than radians?"),
    (1e3, "increments 1000 times too large (mrad rather than rad?)"),
    (1e-3, "increments 1000 times too small (krad? a unit slip?)"),
)
"""Gyro scale factors a unit slip produces, with the likely cause; rates-for-increments and
cumulative angles are tried as well (they depend on the sample rate)."""


@dataclass
class Outlier:
    maneuver: str
    time_s: float
    line: int
    """Line of ``star_tracker.csv`` (the header is line 1)."""
    size_arcsec: float
    """Departure from its neighbours that the motion does not explain (`outlier_distances`), or,
    in an excursion, from the error's trend (`trend_distances`)."""
    mahalanobis: float
    """The same departure in standard deviations of the data's own noise."""
    kind: str = "outlier"
    """``outlier`` (a sample or a few) or ``excursion`` (a run that leaves the trend and comes back)."""


@dataclass
class Findings:
    """What `check` found: errors refuse the campaign; warnings and outliers are recorded."""

    errors: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    outliers: list = field(default_factory=list)
    mounting: dict = field(default_factory=dict)
    """The reference's mounting applied (`align`): quaternion, source and angle."""


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


def _interval_rotations(st_quat) -> np.ndarray:
    """(M-1, 3) body-frame rotation vectors of the star tracker between consecutive samples."""
    r = Rotation.from_quat(st_quat)
    return (r[:-1].inv() * r[1:]).as_rotvec()


def _gyro_at_st(data, increments) -> np.ndarray:
    """(M-1, 3) summed body increments of the first channel set between star-tracker samples."""
    k, frac = data.st_interval()
    cumulative = cumulative_at_st(increments, k, frac)
    return np.diff(cumulative, axis=0)


def _body_increments(data, raw) -> np.ndarray:
    """Body increments of the first channel set from raw channel increments (nominal model),
    so a reinterpretation of the raw columns can be tried."""
    first = data.sets[0]
    index = {c.name: i for i, c in enumerate(data.channels)}
    zeros = ch.ChannelParams.zeros(data.channels)
    return ch.solve_body(raw[:, [index[n] for n in first]], zeros.subset(first))


@dataclass
class Sensed:
    """What both sensors saw during one maneuver, computed once for every check."""

    data: object
    """The maneuver (`preprocess.ManeuverData`)."""
    body: np.ndarray
    """(K, 3) body increments of the first channel set at nominal parameters (rad)."""
    d_gyro: np.ndarray
    """(M-1, 3) those increments summed between star-tracker samples (rad)."""
    d_st: np.ndarray
    """(M-1, 3) the star tracker's rotation between its samples, body axes (rad)."""
    dt: np.ndarray
    """(M-1,) star-tracker sample intervals (s)."""

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


def sense(data) -> Sensed:
    """Both sensors' rotations of one maneuver, for every check of it."""
    body = _body_increments(data, data.increments)
    return Sensed(data, body, _gyro_at_st(data, body), _interval_rotations(data.st_quat), np.diff(data.st_time))


def fit_rotation(d_gyro, d_st, dt, axis: int, bias=True) -> RotationFit:
    """Least squares of the gyro's interval rotations on the star tracker's about all three axes
    and (with ``bias``) a constant rate. The response to rotation about ``axis`` is 1 + scale
    error on that axis and the misalignments across; the other axes' columns take up any motion
    about them (a hand-held trial turns about more than one axis)."""
    excursion = np.ptp(np.cumsum(d_st, axis=0), axis=0)
    x = np.column_stack([d_st, dt] if bias else [d_st])
    coef, *_ = np.linalg.lstsq(x, d_gyro, rcond=None)
    resid = d_gyro - x @ coef
    sigma = 1.4826 * np.median(np.abs(resid - np.median(resid, axis=0)), axis=0) + 1e-15
    info = np.linalg.pinv(x.T @ x)[axis, axis]
    return RotationFit(int(np.argmax(excursion)), float(d_st[:, axis].sum()), excursion, coef[axis],
                       sigma * np.sqrt(info))


CHECK_BLOCK_S = 1.0
"""The rotation checks compare the sensors over blocks of samples at least this long: over a
fast reference's single interval, its noise and any sub-sample timing would bias the slope."""


def _blocked(dt, *series):
    """Sums of consecutive intervals over blocks of at least `CHECK_BLOCK_S` (the dt first)."""
    size = max(1, round(CHECK_BLOCK_S / float(np.median(dt))))
    n = len(dt) // size * size
    return [x[:n].reshape(n // size, size, *x.shape[1:]).sum(axis=1) for x in (dt, *series)]


def _consistent(d_gyro, d_st, dt, axis, sf_bound, mis_bound) -> bool:
    """Whether the gyro's rotation matches the star tracker's within the physical bounds, with
    a bias fitted or (where a rotation at one steady rate leaves it confounded with the
    scale) without; over blocks of `CHECK_BLOCK_S`."""
    dt, d_gyro, d_st = _blocked(dt, d_gyro, d_st)
    return any(_within(fit_rotation(d_gyro, d_st, dt, axis, bias), axis, sf_bound, mis_bound) for bias in (True, False))


def _within(fit: RotationFit, axis: int, sf_bound, mis_bound) -> bool:
    others = [b for b in range(3) if b != axis]
    scale_ok = abs(fit.response[axis] - 1.0) <= sf_bound + DETECTION_SD * fit.response_sd[axis]
    cross_ok = all(abs(fit.response[b]) <= mis_bound + DETECTION_SD * fit.response_sd[b] for b in others)
    determined = DETECTION_SD * fit.response_sd[axis] <= sf_bound
    return bool(scale_ok and cross_ok and determined and fit.axis == axis)


def _limits(channels):
    """Largest physical scale error and misalignment (SI), as the baseline effects declare them."""
    spec = baseline(channels)
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


def rotation_findings(campaign: Campaign, sensed: Sensed, limits, findings: Findings) -> bool:
    """Angle, axis, direction and units of one maneuver's rotation, gyro against star tracker;
    whether it is consistent."""
    m = campaign.maneuver(sensed.data.id)
    a = AXIS_INDEX[m.axis]
    sf_bound, mis_bound, sf_sd = limits
    d_st, dt, d_gyro = sensed.d_st, sensed.dt, sensed.d_gyro
    where = f"maneuver {m.id} ({m.turn})"
    min_angle = reference_noise_rad(sensed) / sf_sd
    blocked_dt, blocked_gyro, blocked_st = _blocked(dt, d_gyro, d_st)
    fit = fit_rotation(blocked_gyro, blocked_st, blocked_dt, a)
    gyro_excursion = np.ptp(np.cumsum(d_gyro, axis=0), axis=0)
    if fit.excursion_rad.max() < min_angle and gyro_excursion.max() < min_angle:
        findings.errors.append(
            f"{where}: neither the star tracker nor the gyros rotate in [{m.t_start}, {m.t_end}] s "
            f"(at most {np.rad2deg(fit.excursion_rad.max()):.3g} deg; a scale factor needs at least "
            f"{np.rad2deg(min_angle):.2g} deg to be told better than its prior): is the window on a hold?")
        return False
    if _consistent(d_gyro, d_st, dt, a, sf_bound, mis_bound):
        n_errors = len(findings.errors)
        if fit.excursion_rad[a] < min_angle:
            findings.errors.append(f"{where}: the star tracker rotates only {np.rad2deg(fit.excursion_rad[a]):.3g} deg "
                                   f"about {m.axis}; a scale factor needs {np.rad2deg(min_angle):.2g} deg")
        elif m.direction == "both":
            turned = {"+": d_st[:, a].clip(min=0).sum(), "-": -d_st[:, a].clip(max=0).sum()}
            missing = [s for s in "+-" if turned[s] < min_angle]
            if missing:
                findings.errors.append(f"{where}: labelled both, but the star tracker turns only "
                                       f"{np.rad2deg(turned[missing[0]]):.3g} deg in the {missing[0]} direction")
        elif np.sign(fit.net_rad) != m.sign:
            findings.errors.append(
                f"{where}: the star tracker and the gyros turn {np.rad2deg(fit.net_rad):+.1f} deg about {m.axis}, "
                f"the opposite of the label's direction {m.direction!r}")
        return len(findings.errors) == n_errors
    st_axis = AXES[fit.axis]
    if st_axis != m.axis and AXES[int(np.argmax(gyro_excursion))] != m.axis:
        findings.errors.append(
            f"{where}: the star tracker and the gyros both rotate mostly about {st_axis} "
            f"({np.rad2deg(fit.excursion_rad[fit.axis]):.1f} deg), not {m.axis}: is the maneuver's axis label wrong?")
        return False
    hint = _diagnose(campaign, sensed, a, sf_bound, mis_bound) or undersampled(sensed)
    if hint:
        findings.errors.append(f"{where}: {hint}")
        return False
    response = ", ".join(f"{AXES[b]} {fit.response[b]:+.4g}" for b in range(3))
    findings.errors.append(
        f"{where}: per unit of the star tracker's rotation about {m.axis} the gyros turn {response} "
        f"(physical: {m.axis} 1 +/- {sf_bound:.2g}, the others within {rad_to_arcsec(mis_bound):.0f} arcsec); "
        f"the star tracker rotates mostly about {st_axis}. Check the channel columns, their axes in "
        f"campaign.yaml and the star tracker's mounting")
    return False


def _diagnose(campaign, sensed: Sensed, a, sf_bound, mis_bound) -> str:
    """The likely cause of an inconsistent rotation: the first reinterpretation that makes it consistent."""
    data, d_gyro, d_st, dt = sensed.data, sensed.d_gyro, sensed.d_st, sensed.dt
    scale = np.ptp(np.cumsum(d_gyro[:, a])) / np.ptp(np.cumsum(d_st[:, a]))
    dt_gyro = float(np.median(data.dt))
    candidates = list(ALTERNATIVES) + [
        (1.0 / dt_gyro, f"rates in rad/s rather than increments? ({1 / dt_gyro:.4g} is the gyro's sample rate)"),
        (180.0 / np.pi / dt_gyro, "rates in deg/s rather than increments in rad?")]
    for factor, cause in candidates:
        if _consistent(d_gyro / factor, d_st, dt, a, sf_bound, mis_bound):
            return f"the gyro rotation is {scale:.4g} times the star tracker's: {cause}"
    i0 = int(np.searchsorted(campaign.gyro_time, data.gyro_time[0]))
    raw = campaign.increments(slice(i0, i0 + len(data.gyro_time)))
    differenced = _gyro_at_st(data, _body_increments(data, np.diff(raw, axis=0)))
    if _consistent(differenced, d_st, dt, a, sf_bound, mis_bound):
        return ("the gyro columns hold a cumulative angle, not the increment since the previous row: "
                "their differences match the star tracker")
    for order, cause in (([1, 2, 3, 0], "scalar first (q0, q1, q2, q3)"), ([3, 0, 1, 2], "in another order")):
        d_reordered = _interval_rotations(data.st_quat[:, order])
        if _consistent(d_gyro, d_reordered, dt, a, sf_bound, mis_bound):
            return (f"the star-tracker quaternions look {cause}: read in that order they match the gyros; "
                    "the contract's q1..q4 are scalar last (docs/interface.md section 1)")
    return ""


MAX_TURN_BETWEEN_REFERENCE_DEG = 90.0
"""The checks compare rotations between reference samples, which are ambiguous beyond half a
turn; a clipped or mis-scaled gyro understates the turn, so they ask for half that."""


def undersampled(sensed: Sensed) -> str:
    """Why the reference is sampled too sparsely for this maneuver's motion, or "": where the
    gyro turns more than `MAX_TURN_BETWEEN_REFERENCE_DEG` between two reference samples, the
    reference's own rotation there may be wrapped by whole turns. Asked only once the rotation
    check has failed and no unit slip explains it (a slip also makes the gyro's turn look
    large); the answer gives the interval the gyro's peak rate needs. A gyro that turns that far
    within one of its own samples is not told to wait for a denser reference: its own data are
    suspect (a cumulative angle, a unit), and the generic rotation message stands."""
    turn_deg = np.rad2deg(np.linalg.norm(sensed.d_gyro, axis=1))
    worst = int(np.argmax(turn_deg))
    if turn_deg[worst] <= MAX_TURN_BETWEEN_REFERENCE_DEG:
        return ""
    peak_deg_s = np.rad2deg(np.max(np.linalg.norm(sensed.body, axis=1) / sensed.data.dt))
    if MAX_TURN_BETWEEN_REFERENCE_DEG / peak_deg_s < np.median(sensed.data.dt):
        return ""
    beyond = int(np.sum(turn_deg > MAX_TURN_BETWEEN_REFERENCE_DEG))
    return (f"the gyro turns {turn_deg[worst]:.0f} deg between the reference samples at {sensed.data.st_time[worst]:.6g} s "
            f"and {sensed.data.st_time[worst + 1]:.6g} s ({beyond} intervals beyond {MAX_TURN_BETWEEN_REFERENCE_DEG:.0f} "
            "deg): the reference's rotation between samples is ambiguous there, so its rotation cannot be checked "
            f"against the gyro's. At the gyro's peak rate, {peak_deg_s:.0f} deg/s, keep the reference at least every "
            f"{MAX_TURN_BETWEEN_REFERENCE_DEG / peak_deg_s:.2g} s (gyrocal import --reference-interval)")


CLIP_BAND = 0.05
"""Gyro samples within this share of a maneuver's peak rate are tested for clipping."""


def saturation_findings(sensed: Sensed, sf_bound, findings: Findings) -> bool:
    """A gyro that reaches its range clips: where its rate sits near its peak, the reference turns
    faster than the gyro says, in the gyro's direction, by more than any scale error and more
    than `DETECTION_SD` times the noise of as many independent reference intervals (on an axis
    that barely turns, the "peak" is noise; conservative, since over consecutive intervals the
    reference's noise partly cancels). Such a maneuver is refused, with the count of clipped samples;
    it is never fitted silently. Returns whether it clipped."""
    data = sensed.data
    rate = np.abs(sensed.body / data.dt[:, None])
    at_st = rate[data.st_interval()[0][1:]]
    for a in range(3):
        peak = rate[:, a].max()
        near = at_st[:, a] >= (1 - CLIP_BAND) * peak
        turned_gyro = np.abs(sensed.d_gyro[near, a]).sum()
        if near.sum() < 5 or turned_gyro == 0:
            continue
        turned_st = np.sum(np.sign(sensed.d_gyro[near, a]) * sensed.d_st[near, a])
        noise = 1.4826 * np.median(np.abs(np.diff(sensed.d_st[:, a]))) / np.sqrt(2)
        excess = turned_st / turned_gyro
        shortfall = turned_st - (1 + 2 * sf_bound) * turned_gyro
        if shortfall > DETECTION_SD * noise * np.sqrt(near.sum()):
            clipped = int((rate[:, a] >= (1 - CLIP_BAND) * peak).sum())
            findings.errors.append(
                f"maneuver {data.id}: {clipped} gyro samples about {AXES[a]} sit within {CLIP_BAND:.0%} of the peak "
                f"rate {np.rad2deg(peak):.1f} deg/s, where the reference turns {excess:.3f} times as fast: the gyro "
                "clips at its range, so its rotation there is not measured. Leave the maneuver out, or cut it "
                "before the first clipped sample")
            return True
    return False


def gap_findings(campaign: Campaign, findings: Findings):
    """Steps longer than `GAP_FACTOR` median steps: an error inside a maneuver's gyro data, a
    warning otherwise. A shorter gap in a rotation is an error only if its increment holds
    the rotation of one step rather than of the whole gap (`lost_increments`)."""
    for name, time in (("gyro.csv", campaign.gyro_time), ("star_tracker.csv", campaign.st_time)):
        lines = campaign.lines[name]
        steps = np.diff(time)
        median = float(np.median(steps))
        for i in np.flatnonzero(steps > GAP_FACTOR * median):
            t0, t1 = time[i], time[i + 1]
            inside = [m.id for m in campaign.maneuvers if t0 < m.t_end and t1 > m.t_start]
            text = (f"{name}: lines {lines[i]}-{lines[i + 1]}: {t1 - t0:.4g} s between samples "
                    f"(median step {median:.4g} s)")
            if inside and name == "gyro.csv":
                findings.errors.append(f"{text} inside maneuver {', '.join(inside)}: the rotation in the gap is "
                                       "lost, so no attitude can be propagated across it. Cut the maneuver at "
                                       "the gap or recover the samples")
            elif inside:
                findings.warnings.append(f"{text} inside maneuver {', '.join(inside)}: fewer star-tracker "
                                         "samples there")
            else:
                findings.warnings.append(f"{text}, outside every maneuver")
    lost_increments(campaign, findings)


SHORT_GAP_FACTOR = 1.5
"""A gyro step this many median steps long is checked for a lost increment."""


def lost_increments(campaign: Campaign, findings: Findings):
    """Gyro rows missing in a rotation. The contract's increment covers the whole step since
    the previous row, so after a missed row it holds the rotation of the longer step; if it
    holds only one median step's worth, the rows' increments were lost, not accumulated."""
    time, inc = campaign.gyro_time, campaign.increments()
    steps = np.diff(time)
    median = float(np.median(steps))
    noise = 1.4826 * np.median(np.abs(np.diff(inc, axis=0)), axis=0) + 1e-15
    for i in np.flatnonzero((steps > SHORT_GAP_FACTOR * median) & (steps <= GAP_FACTOR * median)):
        row = i + 1
        around = [r for r in (row - 2, row - 1, row + 1, row + 2) if 1 <= r < len(time)]
        rate = np.mean(inc[around] / np.diff(time)[np.array(around) - 1, None], axis=0)
        expected = rate * steps[i]
        c = int(np.argmax(np.abs(expected) / noise))
        if abs(expected[c] - inc[row, c]) < DETECTION_SD * noise[c] * np.sqrt(steps[i] / median):
            continue
        if abs(inc[row, c]) < 0.5 * (1 + median / steps[i]) * abs(expected[c]):
            inside = [m.id for m in campaign.maneuvers if time[i] < m.t_end and time[row] > m.t_start]
            findings.errors.append(
                f"gyro.csv: line {campaign.lines['gyro.csv'][row]}: its increment covers {steps[i]:.4g} s but "
                f"holds {inc[row, c] / expected[c] * steps[i]:.3g} s of the rotation its neighbours show "
                f"(channel {campaign.channel_names[c]}"
                + (f", maneuver {', '.join(inside)}" if inside else "")
                + "): rows were dropped and their increments lost")


def clock_offset_s(sensed: Sensed) -> float:
    """Time shift of the gyro clock against the star tracker's that best lines up their rotation
    about the maneuver axis (a positive shift: the gyro's time stamps are late): a coarse then a
    fine grid search of the misfit, refined by a parabola."""
    data = sensed.data
    a = AXIS_INDEX[data.axis]
    theta_gyro = np.concatenate([[0.0], np.cumsum(sensed.body[:, a])])
    theta_st = np.concatenate([[0.0], np.cumsum(sensed.d_st[:, a])])
    t = data.st_time
    span = min(MAX_CLOCK_SEARCH_S, 0.25 * (t[-1] - t[0]))
    step = 0.25 * float(np.median(np.diff(t)))

    # The fit of theta_st on [g, t, 1] for every shift at once: with a line in t projected out of
    # both sides (Frisch-Waugh), its residual sum of squares is |y|^2 - (g.y)^2 / |g|^2.
    line = np.column_stack([t - t[0], np.ones_like(t)])
    q, _ = np.linalg.qr(line)
    y = theta_st - q @ (q.T @ theta_st)

    def misfit(shifts):
        g = np.interp(t[None, :] + shifts[:, None], data.gyro_time, theta_gyro)
        g -= (g @ q) @ q.T
        return y @ y - (g @ y) ** 2 / np.maximum(np.einsum("ij,ij->i", g, g), np.finfo(float).tiny)

    coarse = max(step, 2 * span / CLOCK_SEARCH_POINTS)
    shifts = np.arange(-span, span + coarse, coarse)
    best = shifts[int(np.argmin(misfit(shifts)))]
    shifts = np.arange(best - 2 * coarse, best + 2 * coarse + step, step)
    costs = misfit(shifts)
    i = int(np.clip(np.argmin(costs), 1, len(shifts) - 2))
    c0, c1, c2 = costs[i - 1:i + 2]
    curvature = c0 - 2 * c1 + c2
    offset = 0.5 * (c0 - c2) / curvature if curvature > 0 else 0.0
    return float(shifts[i] + step * np.clip(offset, -1, 1))


def clock_findings(sensed: Sensed, findings: Findings):
    """A clock offset of more than two samples (of the slower sensor) is an error. A shorter
    one whose error at the peak rate exceeds `DETECTION_SD` star-tracker sd is a warning:
    a latency the criticism loop should find (effect ``st_latency``)."""
    data = sensed.data
    offset = clock_offset_s(sensed)
    limit = 2.0 * max(float(np.median(np.diff(data.st_time))), float(np.median(data.dt)))
    where = f"maneuver {data.id}: the gyro and star-tracker rotations line up best when the gyro clock is shifted by"
    if abs(offset) > limit:
        findings.errors.append(
            f"{where} {offset:+.3g} s (more than two samples, {limit:.3g} s): are the two clocks "
            "synchronised, and is each time the end of its sample?")
        return
    d_st = sensed.d_st
    noise_rad = reference_noise_rad(sensed)
    peak_rate = np.max(np.abs(d_st[:, AXIS_INDEX[data.axis]]) / sensed.dt)
    if abs(offset) * peak_rate > DETECTION_SD * noise_rad:
        findings.warnings.append(
            f"{where} {offset:+.3g} s, {rad_to_arcsec(abs(offset) * peak_rate):.0f} arcsec at the peak rate: "
            "a latency or clock offset the baseline model lacks (the library effect st_latency has it)")


def chi2_quantile(q, df):
    """The chi-square quantile as `scipy.stats.chi2.ppf` computes it, from `scipy.special`: validate
    and each preprocess job are processes of their own, and scipy.stats costs 0.3 s to import."""
    return 2 * gammaincinv(df / 2, q)


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


def outlier_distances(sensed: Sensed):
    """Each star-tracker sample's departure from its neighbours (`neighbour_residual` of the error
    of eq. 4, rad, body axes), less what the motion explains, and its squared Mahalanobis
    distance under the robust covariance of those departures: the data's own noise.

    The error between the sensors bends only where the motion does. An error linear in the
    rotation (scale, misalignment), in the rate (a latency or time offset) or in the rate's
    signed square (a nonlinearity) leaves, where the motion bends, a departure proportional to
    the same departure of the cumulative angle, the rate or the square-rate integral; these
    nine regressors are fitted on the inliers and taken out, so only what the motion cannot
    explain remains.
    """
    data, body, err = sensed.data, sensed.body, sensed.departures
    rate = body / data.dt[:, None]
    k, frac = data.st_interval()
    motion = neighbour_residual(np.concatenate([cumulative_at_st(body, k, frac), rate[k],
                                                cumulative_at_st(body * np.abs(rate), k, frac)], axis=1))
    inside = np.ones(len(err), dtype=bool)
    inside[[0, -1]] = False
    cut = chi2_quantile(0.999, 3)
    for _ in range(3):
        coef, *_ = np.linalg.lstsq(motion[inside], err[inside], rcond=None)
        resid = err - motion @ coef
        cov = robust_covariance(resid[inside])
        d2 = mahalanobis2(resid, cov)
        inside = (d2 < cut) & inside
    return resid, d2


def trend_distances(sensed: Sensed):
    """Each star-tracker sample's error between the sensors (eq. 4, nominal parameters, rad, body
    axes) less its trend, the running median over `EXCURSION_TREND_S`, and its squared Mahalanobis
    distance under the robust covariance of those deviations. Scale errors, misalignments and
    biases bend the error slowly and the median follows them; a reference excursion leaves it."""
    err = sensed.error
    window = int(min(len(err), max(3, round(EXCURSION_TREND_S / float(np.median(sensed.dt))))))
    dev = err - median_filter(err, size=(window | 1, 1), mode="nearest")
    return dev, mahalanobis2(dev, robust_covariance(dev))


def excursion_runs(near, beyond, jumps, st_time, max_s: float) -> np.ndarray:
    """Excursions: runs of ``near`` (off the trend beyond a lower cut) that hold a jump (a sample off
    its neighbours, ``jumps``: a wander of the error leaves its trend too, but smoothly) and whose
    core, the samples ``beyond`` the outlier threshold, lasts at most ``max_s`` and lies inside the
    maneuver, so that the error is seen to come back. The run's edges, off the trend but not
    beyond the threshold, go with it, unless they stretch it past twice ``max_s``."""
    n = len(near)
    out = np.zeros(n, dtype=bool)
    for a, b in runs(near):
        core = np.flatnonzero(beyond[a:b]) + a
        if core.size == 0 or not jumps[a:b].any():
            continue
        c0, c1 = core[0], core[-1] + 1
        if c0 == 0 or c1 == n or st_time[c1] - st_time[c0 - 1] > max_s:
            continue
        if st_time[min(b, n - 1)] - st_time[max(a - 1, 0)] <= 2 * max_s:
            out[a:b] = True
        else:
            out[c0:c1] = True
    return out


def mahalanobis2(x, cov) -> np.ndarray:
    """(N,) squared Mahalanobis distance of each row of ``x`` (N, p) under ``cov``."""
    return np.einsum("mi,ij,mj->m", x, np.linalg.pinv(cov), x)


def robust_covariance(x, iterations=5, quantile=0.99) -> np.ndarray:
    """Covariance of the bulk of ``x`` (N, p): refit on the points inside the ``quantile`` ellipsoid,
    corrected for the truncation (a normal's tails are cut, not outliers')."""
    p = x.shape[1]
    scale = 1.4826 * np.median(np.abs(x - np.median(x, axis=0)), axis=0) + 1e-15
    cov = np.diag(scale**2)
    cut = chi2_quantile(quantile, p)
    factor = chdtr(p + 2, cut) / chdtr(p, cut)
    for _ in range(iterations):
        d2 = mahalanobis2(x, cov)
        inside = x[d2 < cut]
        cov = inside.T @ inside / len(inside) / factor
    return cov


def check(campaign: Campaign) -> Findings:
    """Every physical check of a campaign. Outliers are screened with a threshold that keeps
    the expected false alarms per campaign at `OUTLIER_FALSE_ALARMS`; they are listed here
    and left out by `preprocess`."""
    findings = Findings()
    gap_findings(campaign, findings)
    limits = _limits(campaign.channels)
    screened = []
    for m in campaign.maneuvers:
        try:
            data = preprocess.slice_maneuver(campaign, m.id)
        except TelemetryError as exc:
            findings.errors.append(str(exc))
            continue
        sensed = sense(data)
        if saturation_findings(sensed, limits[0], findings) or not rotation_findings(campaign, sensed, limits, findings):
            continue
        clock_findings(sensed, findings)
        missing = classic.missing_holds(data)
        if data.direction == "both":
            findings.warnings.append(f"maneuver {m.id}: turns both ways: the paper's classic method does not apply "
                                     "to it (the full-trajectory fit does)")
        elif missing:
            findings.warnings.append(f"maneuver {m.id}: no inertial hold {' or '.join(missing)} the rotation: "
                                     "the paper's classic method does not apply to it (the full-trajectory "
                                     "fit does)")
        screened.append((data, *outlier_distances(sensed), *trend_distances(sensed)))
    n_total = sum(len(d2) for _, _, d2, _, _ in screened)
    threshold = chdtri(3, OUTLIER_FALSE_ALARMS / max(n_total, 1))
    for data, resid, d2, dev, d2_trend in screened:
        lines = campaign.lines["star_tracker.csv"][np.searchsorted(campaign.st_time, data.st_time)]
        beyond = d2 > threshold
        isolated = isolated_runs(beyond, OUTLIER_MAX_RUN)
        away = excursion_runs(d2_trend > EXCURSION_EDGE_CUT, d2_trend > threshold, beyond, data.st_time,
                              EXCURSION_MAX_S) & ~isolated
        for j in np.flatnonzero(isolated):
            findings.outliers.append(Outlier(data.id, float(data.st_time[j]), int(lines[j]),
                                             float(rad_to_arcsec(np.linalg.norm(resid[j]))),
                                             float(np.sqrt(d2[j]))))
        for j in np.flatnonzero(away):
            findings.outliers.append(Outlier(data.id, float(data.st_time[j]), int(lines[j]),
                                             float(rad_to_arcsec(np.linalg.norm(dev[j]))),
                                             float(np.sqrt(d2_trend[j])), "excursion"))
        beside = np.convolve(away, np.ones(2 * OUTLIER_REACH + 1), mode="same") > 0
        structure = int((beyond & ~isolated & ~beside).sum())
        if structure:
            findings.warnings.append(
                f"maneuver {data.id}: {structure} star-tracker samples in runs of more than {OUTLIER_MAX_RUN} depart "
                "from their neighbours beyond the noise: structure the model should explain, not outliers; "
                "they stay in the fit")
    return findings


def runs(mask):
    """``(start, end)`` of each run of consecutive True in ``mask``, ``end`` past its last entry."""
    edges = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    return zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1))


def isolated_runs(mask, max_run: int) -> np.ndarray:
    """The entries of ``mask`` that sit in runs of at most ``max_run`` consecutive True."""
    out = np.zeros(len(mask), dtype=bool)
    for a, b in runs(mask):
        if b - a <= max_run:
            out[a:b] = True
    return out


def estimate_mounting(campaign: Campaign) -> tuple:
    """Coarse alignment of the attitude reference: the rotation taking its frame into body axes that
    best maps its interval rotations onto the gyros' (Wahba's problem, `Rotation.align_vectors`),
    over every maneuver, and the sd of its angle about each body axis (deg). It absorbs the
    common rotation of the gyro misalignments too: after it, misalignments are relative to the
    reference as the data align it. About an axis no maneuver turns across, it is not determined."""
    sensed = [sense(preprocess.slice_maneuver(campaign, m.id)) for m in campaign.maneuvers]
    gyro, reference = np.vstack([s.d_gyro for s in sensed]), np.vstack([s.d_st for s in sensed])
    mounting, rssd, sensitivity = Rotation.align_vectors(gyro, reference, return_sensitivity=True)
    variance = rssd**2 / max(len(gyro) - 3, 1)
    return mounting, np.rad2deg(np.sqrt(np.diag(sensitivity) * variance))


def aligned(campaign: Campaign, mounting: Rotation) -> Campaign:
    """The campaign with its reference attitudes turned into body axes: ``R_body = R_ref M^-1`` for a
    mounting ``M`` that takes reference-frame vectors into body axes."""
    quat = campaign.st_quat.copy()
    valid = campaign.st_valid == 1
    quat[valid] = (Rotation.from_quat(quat[valid]) * mounting.inv()).as_quat()
    return replace(campaign, st_quat=quat)


def align(campaign: Campaign) -> tuple:
    """The reference's mounting from ``campaign.yaml`` (``star_tracker.mounting``): a nominal
    quaternion, refined by the data's coarse alignment when it is off by more than the largest
    misalignment; or ``estimate``: the data's alignment alone. Returns the aligned campaign
    and what was applied."""
    declared = campaign.star_tracker.get("mounting")
    if declared is None:
        return campaign, {}
    sd_deg = None
    if declared == "estimate":
        (mounting, sd_deg), source = estimate_mounting(campaign), "estimated from the data"
    else:
        mounting, source = Rotation.from_quat(declared), "nominal (campaign.yaml)"
        residual, residual_sd = estimate_mounting(aligned(campaign, mounting))
        if residual.magnitude() > _limits(campaign.channels)[1]:
            mounting, source, sd_deg = residual * mounting, "nominal, refined by the data's alignment", residual_sd
    applied = {"quat": mounting.as_quat().tolist(), "source": source,
               "angle_deg": float(np.rad2deg(mounting.magnitude()))}
    if sd_deg is not None:
        applied["sd_deg"] = {a: float(v) for a, v in zip(AXES, sd_deg)}
    return aligned(campaign, mounting), applied


def read_checked(directory, campaign=None):
    """Read a campaign (format, `telemetry.read_campaign`; or take ``campaign``, the directory's
    as that read it), turn its reference into body axes (`align`) and check its physics; every
    error found is raised at once in one `TelemetryError`. Returns the aligned campaign and its
    `Findings`."""
    campaign, mounting = align(read_campaign(directory) if campaign is None else campaign)
    findings = check(campaign)
    findings.mounting = mounting
    if findings.errors:
        listed = "\n".join(f"  - {e}" for e in findings.errors)
        raise TelemetryError(f"{directory}: the data are not physically consistent "
                             f"({len(findings.errors)} finding(s)):\n{listed}")
    return campaign, findings


def summary(campaign: Campaign, findings: Findings) -> str:
    """What ``gyrocal validate`` prints: the campaign, then the warnings and outliers."""
    lines = [format_summary(campaign)]
    if findings.mounting:
        lines.append(f"  reference  mounting {findings.mounting['source']}: {findings.mounting['angle_deg']:.3f} deg "
                     f"from body axes"
                     + ("; sd about " + ", ".join(f"{a} {v:.3g}" for a, v in findings.mounting["sd_deg"].items())
                        + " deg" if "sd_deg" in findings.mounting else ""))
    if campaign.st_renormalised:
        lines.append(f"  renormalised {campaign.st_renormalised} star-tracker quaternions (norm off 1 by more "
                     f"than {UNIT_NORM_TOL:g}, as rounding leaves them)")
    for w in findings.warnings:
        lines.append(f"  warning: {w}")
    if findings.outliers:
        away = sum(o.kind == "excursion" for o in findings.outliers)
        lines.append(f"  star-tracker outliers, left out of the fit: {len(findings.outliers)}"
                     + (f", {away} of them in excursions (off the error's trend and back within "
                        f"{EXCURSION_MAX_S:g} s)" if away else "")
                     + (" (the 20 largest; all in input.json)" if len(findings.outliers) > 20 else ""))
        for o in sorted(findings.outliers, key=lambda o: -o.mahalanobis)[:20]:
            lines.append(f"    {o.maneuver:<12} line {o.line:>7}  t = {o.time_s:.2f} s  {o.size_arcsec:8.1f} arcsec "
                         f"({o.mahalanobis:.1f} sd)" + ("  excursion" if o.kind == "excursion" else ""))
    return "\n".join(lines)
