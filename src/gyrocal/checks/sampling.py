"""Sampling and clocks: gaps and lost gyro rows, and the clock offset between the two sensors."""

import numpy as np

from gyrocal.checks.finding import Findings
from gyrocal.checks.sensing import Sensed, reference_noise_rad
from gyrocal.inference.identification import DETECTION_SD
from gyrocal.io.telemetry import Campaign
from gyrocal.model.units import AXIS_INDEX, rad_to_arcsec

__all__ = [
    "CLOCK_SEARCH_POINTS", "GAP_FACTOR", "MAX_CLOCK_SEARCH_S", "SHORT_GAP_FACTOR", "clock_findings", "clock_offset_s",
    "gap_findings", "lost_increments"
]

GAP_FACTOR = 3.0
"""A time step longer than this many median steps is a gap."""


MAX_CLOCK_SEARCH_S = 60.0
"""The clock-offset search spans at most this far either way."""

CLOCK_SEARCH_POINTS = 400
"""Shifts of the clock-offset search's coarse pass; a fine pass at a quarter of a star-tracker
step follows about its best (the misfit varies smoothly with the shift)."""


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
        findings.refuse("clock",
            f"{where} {offset:+.3g} s (more than two samples, {limit:.3g} s): are the two clocks "
            "synchronised, and is each time the end of its sample?")
        return
    d_st = sensed.d_st
    noise_rad = reference_noise_rad(sensed)
    peak_rate = np.max(np.abs(d_st[:, AXIS_INDEX[data.axis]]) / sensed.dt)
    if abs(offset) * peak_rate > DETECTION_SD * noise_rad:
        findings.warn("clock",
            f"{where} {offset:+.3g} s, {rad_to_arcsec(abs(offset) * peak_rate):.0f} arcsec at the peak rate: "
            "a latency or clock offset the baseline model lacks (the library effect st_latency has it)")


