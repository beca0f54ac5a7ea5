"""Sampling and clocks: gaps and lost gyro rows, and the clock offset between the two sensors."""

import numpy as np

from gyrocal.checks.sensing import Sensed, comparable, reference_noise_rad
from gyrocal.finding import Findings
from gyrocal.inference.fit.identification import DETECTION_SD
from gyrocal.io.telemetry import Campaign
from gyrocal.model.units import rad_to_arcsec

__all__ = [
    "CLOCK_SEARCH_POINTS",
    "GAP_FACTOR",
    "MAX_CLOCK_SEARCH_S",
    "MAX_GYRO_RATE_RAD_S",
    "MAX_GYRO_STEP_S",
    "RATE_TOLERANCE",
    "SHIFTS_AT_ONCE",
    "SHORT_GAP_FACTOR",
    "clock_findings",
    "clock_offset_s",
    "clock_search",
    "declared_rate_findings",
    "extreme_findings",
    "gap_findings",
    "interval_findings",
    "lost_increments"
]

GAP_FACTOR = 3.0
"""A time step longer than this many median steps is a gap."""


MAX_CLOCK_SEARCH_S = 60.0
"""The clock-offset search spans at most this far either way."""

CLOCK_SEARCH_POINTS = 400
"""Shifts of the clock-offset search's coarse pass; a fine pass at a quarter of a star-tracker
step follows about its best (the misfit varies smoothly with the shift)."""

SHIFTS_AT_ONCE = 64
"""The clock-offset search interpolates this many shifts at once: all of a fine pass's 1100 at once
over a 200-s trial at 286 Hz made 0.5-GB arrays per axis (7 of validate's 12 s and 1 GB)."""


MAX_GYRO_RATE_RAD_S = 100.0
"""No gyro of a spacecraft or an IMU senses a rate this fast (5,700 deg/s; a MEMS gyro's range is at most
a few thousand deg/s, a DTG's tens): an increment that implies it is a corrupt value, not a rotation."""


def extreme_findings(campaign: Campaign, findings: Findings) -> bool:
    """Gyro increments no gyro can sense (`MAX_GYRO_RATE_RAD_S`): inside a maneuver a refusal naming
    the line, the channel and the value (propagating them would only fail deep in the kinematics);
    outside every maneuver, where nothing reads them, a warning naming them. Returns whether any
    maneuver holds one."""
    inc, time = campaign.increments(), campaign.gyro_time
    with np.errstate(over="ignore"):  # an overflow is itself the finding
        rate = np.abs(inc[1:]) / np.diff(time)[:, None]
    bad_rows, bad_cols = np.nonzero(~(rate <= MAX_GYRO_RATE_RAD_S))
    if not bad_rows.size:
        return False
    rows = bad_rows + 1
    lines = campaign.lines["gyro.csv"][rows]
    inside = np.zeros(rows.size, dtype=bool)
    for m in campaign.maneuvers:
        inside |= (time[rows] > m.t_start) & (time[rows - 1] < m.t_end)
    def listed(mask):
        shown = [f"line {lines[k]} ({campaign.channel_names[bad_cols[k]]} = {inc[rows[k], bad_cols[k]]:.6g} rad)"
                 for k in np.flatnonzero(mask)[:5]]
        return ", ".join(shown) + (f" and {int(mask.sum()) - 5} more" if mask.sum() > 5 else "")
    if inside.any():
        findings.refuse("sampling", f"gyro.csv: {listed(inside)}: an increment faster than any gyro senses "
                        f"({MAX_GYRO_RATE_RAD_S:g} rad/s) inside a maneuver: a corrupt value. Correct or remove "
                        "the row, or cut the maneuver before it")
    if (~inside).any():
        findings.warn("sampling", f"gyro.csv: {listed(~inside)}: an increment faster than any gyro senses, outside "
                      "every maneuver (not used, but a sign of corrupt data)")
    return bool(inside.any())


MAX_GYRO_STEP_S = 1.0
"""A gyro is read at least once a second (a DTG's or a MEMS triad's rate is tens to hundreds of Hz):
a longer median step says the times are not in seconds."""


RATE_TOLERANCE = 0.01
"""A sampling rate declared in campaign.yaml (``gyro.rate_hz``, ``star_tracker.rate_hz``) and the data's
median step agree to within 1 %: a clock's drift is far less, a unit slip or a thinned or resampled
file far more."""


def declared_rate_findings(campaign: Campaign, findings: Findings) -> bool:
    """Each file's median step against the rate campaign.yaml declares for it, if it declares one.
    Returns whether it refused."""
    refused = False
    for name, section, time in (("gyro.csv", "gyro", campaign.gyro_time),
                                ("star_tracker.csv", "star_tracker", campaign.st_time)):
        declared = (getattr(campaign, section) or {}).get("rate_hz")
        if declared is None or len(time) < 2:
            continue
        step = float(np.median(np.diff(time)))
        if abs(step * declared - 1.0) > RATE_TOLERANCE:
            findings.refuse(
                "sampling", f"{name}: the median step between samples is {step:.6g} s ({1 / step:.6g} Hz), but "
                f"campaign.yaml declares {section}: {{rate_hz: {declared:g}}}, a {1 / declared:.6g} s step: times in "
                f"another unit, a thinned or resampled file, or a wrong rate? Correct {name}'s times or "
                f"campaign.yaml's {section}.rate_hz", figure=1 / step, threshold=float(declared), unit="Hz",
                where=f"{name} against campaign.yaml {section}.rate_hz")
            refused = True
    return refused


def interval_findings(campaign: Campaign, findings: Findings) -> bool:
    """The sample intervals make sense: each file's against the rate campaign.yaml declares for it
    (`declared_rate_findings`), the times are seconds (a median gyro step over
    `MAX_GYRO_STEP_S`: milliseconds?), and the gyro is read at least as often as the reference,
    since the error model integrates the gyro between reference samples (a sparser gyro would
    interpolate the rotation, and its intervals would be too narrow). Returns whether it refused."""
    if declared_rate_findings(campaign, findings):
        return True
    gyro_step = float(np.median(np.diff(campaign.gyro_time)))
    st_step = float(np.median(np.diff(campaign.st_time)))
    if gyro_step > st_step * (1 + 1e-6):
        findings.refuse("sampling", f"the gyro is read every {gyro_step:.4g} s (median), the star tracker every "
                        f"{st_step:.4g} s: gyrocal integrates the gyro between reference samples and needs at least one "
                        "gyro sample per reference interval. Thin the reference (gyrocal import --reference-interval) "
                        "or give the gyro at its full rate", figure=gyro_step, threshold=st_step, unit="s")
        return True
    if gyro_step > MAX_GYRO_STEP_S:
        thousandth = gyro_step * 1e-3 <= MAX_GYRO_STEP_S and st_step > 10 * MAX_GYRO_STEP_S
        cause = (f"times in milliseconds? (x 1e-3: a {gyro_step * 1e-3:.4g} s step)" if thousandth
                 else "too sparse to propagate an attitude")
        findings.refuse("sampling", f"gyro.csv: the median step between gyro samples is {gyro_step:.6g} s: {cause}. The "
                        "contract's times are seconds (docs/interface.md section 3)", figure=gyro_step,
                        threshold=MAX_GYRO_STEP_S, unit="s")
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
                findings.refuse("sampling", f"{text} inside maneuver {', '.join(inside)}: the rotation in the gap is "
                                       "lost, so no attitude can be propagated across it. Cut the maneuver at "
                                       "the gap or recover the samples")
            elif inside:
                findings.warn("sampling", f"{text} inside maneuver {', '.join(inside)}: fewer star-tracker "
                                         "samples there")
            else:
                findings.warn("sampling", f"{text}, outside every maneuver")
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
            findings.refuse("sampling",
                f"gyro.csv: line {campaign.lines['gyro.csv'][row]}: its increment covers {steps[i]:.4g} s but "
                f"holds {inc[row, c] / expected[c] * steps[i]:.3g} s of the rotation its neighbours show "
                f"(channel {campaign.channel_names[c]}"
                + (f", maneuver {', '.join(inside)}" if inside else "")
                + "): rows were dropped and their increments lost")


def clock_offset_s(sensed: Sensed) -> float:
    """Time shift of the gyro clock against the star tracker's that best lines up their rotations
    about all three axes together (a positive shift: the gyro's time stamps are late), for any
    motion: one common scale, and a line in time per axis (its start and drift), fitted at every
    shift; a coarse then a fine grid search of the misfit, refined by a parabola. On a single-axis
    maneuver the axes that do not turn add next to nothing. An interval the gyro turns too far in for
    the reference's rotation to show (`sensing.comparable`: a gap) takes the gyro's: it says nothing of
    the clock, and a wrapped turn would."""
    return clock_search(sensed)[0]


def clock_search(sensed: Sensed) -> tuple:
    """`clock_offset_s`, how much the shift lowers the misfit against none, and the misfit left at it
    (rad^2, summed over the reference's samples and axes)."""
    data = sensed.data
    theta_gyro = np.vstack([np.zeros(3), np.cumsum(sensed.body, axis=0)])
    d_st = sensed.d_st.copy()
    far = ~comparable(sensed.d_gyro)  # across a gap the reference's rotation may be wrapped: the gyro's bridges it
    if far.any() and not far.all():
        d_st[far] = sensed.d_gyro[far]
    theta_st = np.vstack([np.zeros(3), np.cumsum(d_st, axis=0)])
    t = data.st_time
    span = min(MAX_CLOCK_SEARCH_S, 0.25 * (t[-1] - t[0]))
    step = 0.25 * float(np.median(np.diff(t)))

    # The fit of theta_st on [c g, t, 1] (per axis) for every shift at once: with a line in t projected
    # out of both sides (Frisch-Waugh), its residual sum of squares is |y|^2 - (g.y)^2 / |g|^2, the
    # dot products summed over the three axes.
    line = np.column_stack([t - t[0], np.ones_like(t)])
    q, _ = np.linalg.qr(line)
    y = theta_st - q @ (q.T @ theta_st)

    def misfit_of(shifts):
        cross, norm = 0.0, 0.0
        for a in range(3):
            g = np.interp(t[None, :] + shifts[:, None], data.gyro_time, theta_gyro[:, a])
            g -= (g @ q) @ q.T
            cross = cross + g @ y[:, a]
            norm = norm + np.einsum("ij,ij->i", g, g)
        return np.sum(y * y) - cross ** 2 / np.maximum(norm, np.finfo(float).tiny)

    def misfit(shifts):
        """`misfit_of` over `SHIFTS_AT_ONCE` shifts at a time: the same numbers, arrays of a cache's size."""
        return np.concatenate([misfit_of(shifts[i:i + SHIFTS_AT_ONCE]) for i in range(0, len(shifts), SHIFTS_AT_ONCE)])

    coarse = max(step, 2 * span / CLOCK_SEARCH_POINTS)
    shifts = np.arange(-span, span + coarse, coarse)
    best = shifts[int(np.argmin(misfit(shifts)))]
    shifts = np.arange(best - 2 * coarse, best + 2 * coarse + step, step)
    costs = misfit(shifts)
    i = int(np.clip(np.argmin(costs), 1, len(shifts) - 2))
    c0, c1, c2 = costs[i - 1:i + 2]
    curvature = c0 - 2 * c1 + c2
    offset = 0.5 * (c0 - c2) / curvature if curvature > 0 else 0.0
    best = float(shifts[i] + step * np.clip(offset, -1, 1))
    at_zero, at_best = misfit(np.array([0.0, best]))
    return best, float(at_zero - at_best), float(at_best)


def clock_findings(sensed: Sensed, findings: Findings):
    """A clock offset of more than two samples (of the slower sensor) is an error, where it lowers the
    misfit by `DETECTION_SD` standard errors of what the shift leaves (a maneuver that turns too little
    does not pin the clock: a warning says it was not checked). A shorter one is
    a warning where the error it leaves over the maneuver's turning samples (the offset times the
    rate, on each) stands out of the reference's noise by `DETECTION_SD` standard errors and the
    offset is at least half a gyro sample (finer, it is within the time tags' resolution): a
    latency of one gyro sample shows over a long slew. The criticism loop should then find it (effect
    ``st_latency``)."""
    data = sensed.data
    offset, gain, left = clock_search(sensed)
    limit = 2.0 * max(float(np.median(np.diff(data.st_time))), float(np.median(data.dt)))
    where = f"maneuver {data.id}: the gyro and star-tracker rotations line up best when the gyro clock is shifted by"
    if abs(offset) > limit:
        z_fit = float(np.sqrt(max(gain, 0.0) / max(left / (3 * len(data.st_time)), np.finfo(float).tiny)))
        if z_fit < DETECTION_SD:
            findings.warn("clock",
                f"{where} {offset:+.3g} s, but that shift lowers their misfit by {z_fit:.2g} sd only (the "
                f"maneuver turns too little to pin the clock; {DETECTION_SD:g} sd would): the clocks are not checked "
                "on it", figure=float(offset), unit="s")
            return
        findings.refuse("clock",
            f"{where} {offset:+.3g} s (more than two samples, {limit:.3g} s; it lowers their misfit by "
            f"{z_fit:.2g} sd): are the two clocks synchronised, and is each time the end of its sample?")
        return
    noise_rad = reference_noise_rad(sensed)
    rate = np.linalg.norm(sensed.d_st, axis=1) / sensed.dt
    peak_rate = float(np.max(rate))
    turning = int(np.sum(rate > 0.5 * peak_rate))
    z = abs(offset) * peak_rate * np.sqrt(max(turning, 1)) / noise_rad
    if z > DETECTION_SD and abs(offset) >= 0.5 * float(np.median(data.dt)):
        findings.warn("clock",
            f"{where} {offset:+.3g} s, {rad_to_arcsec(abs(offset) * peak_rate):.0f} arcsec at the peak rate on "
            f"{turning} turning samples ({z:.0f} sd of the reference's noise): a latency or clock offset the "
            "baseline model lacks (the library effect st_latency has it)", figure=float(offset), unit="s")


