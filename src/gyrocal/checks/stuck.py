"""Dead, stuck and frozen sensors, and single corrupt gyro cells, before any fit.

A gyro channel that reads exactly zero or one constant while the reference turns about its input
axis; a reference that repeats its attitude exactly (``valid = 1``) while the gyros turn; a single
gyro increment that leaves its neighbours by more than the reference's motion allows (a cell
that lost its exponent: 9.84e-05 written 9.84). Each is named with its file, column, lines and
likely cause. The thresholds are physical: the noise stated in ``campaign.yaml`` or shown by the
data (the larger), the rotation the other sensor shows, and the scale and misalignment bounds
the baseline effects declare; each by `DETECTION_SD` of the noise, so a clean campaign is not
flagged. Only data inside a maneuver are judged: nothing else is read."""

import numpy as np
from scipy.special import ndtri

from gyrocal.checks.sensing import interval_rotations
from gyrocal.finding import Findings
from gyrocal.inference.fit.identification import DETECTION_SD
from gyrocal.io.telemetry import Campaign
from gyrocal.model.units import AXIS_INDEX, arcsec_to_rad

__all__ = ["MIN_STUCK_S", "SPIKE_FALSE_ALARMS", "SPIKE_REFUSAL_FACTOR", "stuck_findings"]

SPIKE_FALSE_ALARMS = 0.01
"""Expected false alarms per campaign of the single-cell test (over every channel's samples)."""

MIN_RUN_SAMPLES = 5
"""A stuck channel repeats one value at least this many samples, and over two reference intervals."""

MIN_STUCK_S = 1.0
"""And for at least this long: a quantised MEMS gyro reads one value (often 0) for a few milliseconds
as its rate crosses a quantum (BROAD's trials: runs of 5-6 samples at 286 Hz); a dead channel stays
dead for the rest of a maneuver."""

SPIKE_REFUSAL_FACTOR = 10.0
"""A single cell is refused only where it leaves its neighbours by this many times what the motion
and noise allow (a lost exponent or digit: 1e3 and more); a smaller excess is warned of, with its
line: a real hand-held motion's jerk reaches a few times the reference's rate between its samples."""


def _robust_sd(x) -> float:
    x = np.asarray(x, dtype=float)
    return float(1.4826 * np.median(np.abs(x - np.median(x)))) if x.size else 0.0


class _Window:
    """One maneuver's data as the checks here need them: valid reference samples, the reference's
    cumulative rotation (body axes) at them, each channel's cumulative angle at them, the noises."""

    def __init__(self, campaign: Campaign, m):
        valid = (campaign.st_valid == 1) & (campaign.st_time >= m.t_start) & (campaign.st_time <= m.t_end)
        self.m = m
        self.st_rows = np.flatnonzero(valid)
        self.st_time = campaign.st_time[valid]
        self.d_st = interval_rotations(campaign.st_quat[valid]) if valid.sum() > 1 else np.zeros((0, 3))
        self.ref_cum = np.vstack([np.zeros(3), np.cumsum(self.d_st, axis=0)])
        g = (campaign.gyro_time > m.t_start) & (campaign.gyro_time <= m.t_end)
        self.g_rows = np.flatnonzero(g)
        time = campaign.gyro_time
        self.dt_g = float(np.median(np.diff(time)))
        self.dt_st = float(np.median(np.diff(self.st_time))) if self.st_time.size > 1 else np.inf
        inc = campaign.increments()
        g0 = max(self.g_rows[0] - 1, 0) if self.g_rows.size else 0
        span = slice(g0, self.g_rows[-1] + 1 if self.g_rows.size else 0)
        cum = np.vstack([np.zeros(inc.shape[1]), np.cumsum(inc[span][1:], axis=0)])
        self.gyro_cum = np.column_stack([np.interp(self.st_time, time[span], cum[:, c]) for c in range(inc.shape[1])]) \
            if cum.shape[0] > 1 else np.zeros((self.st_time.size, inc.shape[1]))
        stated = campaign.star_tracker
        sigma_st = arcsec_to_rad(max(stated.get("sigma_cross_arcsec", 0.0), stated.get("sigma_about_arcsec", 0.0)))
        shown = _robust_sd(np.diff(self.d_st, axis=0).ravel()) / np.sqrt(6.0) if len(self.d_st) > 2 else 0.0
        self.sigma_st = max(sigma_st, shown)
        """One reference sample's noise (rad): stated, or as its rotations' second differences show it."""
        arw = np.deg2rad(campaign.gyro.get("arw_deg_sqrt_h", 0.0)) / 60.0 * np.sqrt(self.dt_g)
        rows = inc[self.g_rows] if self.g_rows.size > 2 else np.zeros((3, inc.shape[1]))
        curvature = rows[1:-1] - 0.5 * (rows[:-2] + rows[2:])
        self.sigma_inc = np.maximum(arw, np.array([_robust_sd(curvature[:, c]) for c in range(inc.shape[1])])
                                    / np.sqrt(1.5))
        """Each channel's noise per increment (rad): the stated walk, or what its data show."""
        d_gyro = np.diff(self.gyro_cum, axis=0)
        axes = [AXIS_INDEX[c.axis] for c in campaign.channels]
        dt = np.diff(self.st_time)
        quiet = np.abs(self.d_st) <= DETECTION_SD * np.sqrt(2.0) * self.sigma_st
        self.bias = np.array([abs(np.median((d_gyro[quiet[:, a], c] - self.d_st[quiet[:, a], a]) / dt[quiet[:, a]]))
                              if quiet[:, a].sum() >= MIN_RUN_SAMPLES else 0.0 for c, a in enumerate(axes)])
        """Each channel's bias (rad/s): its rate less the reference's about its axis, the median over
        the intervals where the reference does not visibly turn about that axis (the holds)."""

    def at(self, t0, t1):
        """The first and last reference samples within [t0, t1], or None."""
        k0, k1 = np.searchsorted(self.st_time, t0, side="left"), np.searchsorted(self.st_time, t1, side="right") - 1
        return (int(k0), int(k1)) if k1 > k0 else None


def stuck_findings(campaign: Campaign, limits, findings: Findings) -> bool:
    """Dead or stuck channels, frozen reference stretches and corrupt single gyro cells inside the
    maneuvers; returns whether any refused (the per-maneuver physics would only restate them)."""
    sf_bound, mis_bound, _ = limits
    windows = [_Window(campaign, m) for m in campaign.maneuvers]
    windows = [w for w in windows if w.st_time.size > 2 and w.g_rows.size > 2]
    before = len(findings.errors)
    _stuck_channels(campaign, windows, sf_bound, mis_bound, findings)
    _frozen_reference(campaign, windows, findings)
    _spikes(campaign, windows, sf_bound, findings)
    return len(findings.errors) > before


def _runs(x, min_length):
    """(start, end) row ranges, end inclusive, over which ``x`` repeats one value exactly."""
    same = np.concatenate([[False], x[1:] == x[:-1], [False]])
    edges = np.flatnonzero(np.diff(same.astype(int)))
    return [(int(s), int(e)) for s, e in zip(edges[::2], edges[1::2]) if e - s + 1 >= min_length]


def _stuck_channels(campaign, windows, sf_bound, mis_bound, findings):
    lines, time = campaign.lines["gyro.csv"], campaign.gyro_time
    for c, channel in enumerate(campaign.channels):
        a = AXIS_INDEX[channel.axis]
        x = campaign.gyro_columns[channel.name]
        for start, end in _runs(x, MIN_RUN_SAMPLES):
            if time[end] - time[max(start - 1, 0)] < MIN_STUCK_S:
                continue
            failed = []
            for w in windows:
                span = w.at(time[max(start - 1, 0)], time[end])
                if span is None or (w.st_time[span[1]] - w.st_time[span[0]]) < 2 * w.dt_st:
                    continue
                k0, k1 = span
                theta = w.ref_cum[k1] - w.ref_cum[k0]
                gyro = w.gyro_cum[k1, c] - w.gyro_cum[k0, c]
                duration = w.st_time[k1] - w.st_time[k0]
                n = duration / w.dt_g
                tol = (sf_bound * abs(theta[a]) + mis_bound * np.abs(np.delete(theta, a)).sum() + w.bias[c] * duration
                       + DETECTION_SD * (np.sqrt(2.0) * w.sigma_st + w.sigma_inc[c] * np.sqrt(n)))
                if abs(gyro - theta[a]) > tol:
                    failed.append(f"{w.m.id}: {np.rad2deg(theta[a]):+.3g} deg, read {np.rad2deg(gyro):+.3g} deg")
            if failed:
                value = "exactly 0" if x[start] == 0 else f"the constant {x[start]:.6g} rad"
                findings.refuse(
                    "stuck",
                    f"gyro.csv, column '{channel.name}', lines {lines[start]}-{lines[end]}: reads {value} for "
                    f"{end - start + 1} samples ({time[end] - time[max(start - 1, 0)]:.1f} s) while the reference turns "
                    f"about {channel.axis}, its input axis ({'; '.join(failed)}): a dead or stuck channel. Remove the "
                    "channel from campaign.yaml and gyro.csv, or cut the maneuvers where it is stuck",
                    where=f"gyro.csv:{lines[start]}-{lines[end]}:{channel.name}")
                continue
            inside = [w.m.id for w in windows if time[end] > w.m.t_start and time[max(start - 1, 0)] < w.m.t_end]
            log_chance = _repeat_log_chance(x, start, end)
            if inside and log_chance + np.log10(len(x) * len(campaign.channels)) < np.log10(STUCK_FALSE_ALARMS):
                value = "exactly 0" if x[start] == 0 else f"the constant {x[start]:.6g} rad"
                findings.refuse(
                    "stuck",
                    f"gyro.csv, column '{channel.name}', lines {lines[start]}-{lines[end]}: reads {value} for "
                    f"{end - start + 1} samples ({time[end] - time[max(start - 1, 0)]:.1f} s) inside maneuver(s) "
                    f"{', '.join(inside)}, where its own noise elsewhere repeats a value that long by chance "
                    f"once in 1e{-log_chance:.0f}: a dead or stuck channel. Remove the channel from campaign.yaml and "
                    "gyro.csv, or cut the maneuvers where it is stuck",
                    where=f"gyro.csv:{lines[start]}-{lines[end]}:{channel.name}")


STUCK_FALSE_ALARMS = 0.01
"""Expected false alarms per campaign of the test of a run's length against the channel's noise."""

REPEAT_BLOCK = 100
"""The rate at which a channel repeats its previous value is taken in blocks of this many samples,
the highest of them: where the noise is smallest against the quantum (a hold), it repeats most."""


def _repeat_log_chance(x, start, end) -> float:
    """The log10 of the chance that the channel's noise repeats one value over rows ``start..end``: its highest rate
    of repeats over `REPEAT_BLOCK` samples outside the run, to the power of the repeats in the run
    (0 where the rest of the channel is too short to tell)."""
    same = (x[1:] == x[:-1]).astype(float)
    keep = np.ones(same.size, dtype=bool)
    keep[max(start - 1, 0):end] = False
    rest = same[keep]
    n = rest.size // REPEAT_BLOCK * REPEAT_BLOCK
    if n < 10 * REPEAT_BLOCK:
        return 0.0
    rate = float(rest[:n].reshape(-1, REPEAT_BLOCK).mean(axis=1).max())
    return float((end - start) * np.log10(min(max(rate, 1.0 / REPEAT_BLOCK), 1.0)))


def _body_turn(campaign, w, k0, k1):
    """The gyros' rotation (rad, per body axis: the median of the channels on that axis) between
    reference samples k0 and k1 of window ``w``."""
    turn = w.gyro_cum[k1] - w.gyro_cum[k0]
    axes = np.array([AXIS_INDEX[c.axis] for c in campaign.channels])
    return np.array([np.median(turn[axes == a]) if (axes == a).any() else 0.0 for a in range(3)]), axes


def _frozen_reference(campaign, windows, findings):
    lines = campaign.lines["star_tracker.csv"]
    for w in windows:
        quat = campaign.st_quat[w.st_rows]
        for k0, k1 in _runs_rows(quat):
            if k1 <= k0:
                continue
            turn, axes = _body_turn(campaign, w, k0, k1)
            duration = w.st_time[k1] - w.st_time[k0]
            n = duration / w.dt_g
            bias = np.array([w.bias[axes == a].max() if (axes == a).any() else 0.0 for a in range(3)])
            noise = np.array([w.sigma_inc[axes == a].max() if (axes == a).any() else 0.0 for a in range(3)])
            tol = bias * duration + DETECTION_SD * (np.sqrt(2.0) * w.sigma_st + noise * np.sqrt(n))
            if (np.abs(turn) > tol).any():
                r0, r1 = w.st_rows[k0], w.st_rows[k1]
                findings.refuse(
                    "frozen",
                    f"star_tracker.csv, columns q1..q4, lines {lines[r0]}-{lines[r1]}: the attitude repeats exactly "
                    f"for {k1 - k0 + 1} samples ({duration:.1f} s, valid = 1) while the gyros turn "
                    f"{np.rad2deg(np.linalg.norm(turn)):.3g} deg (maneuver {w.m.id}; the noise allows "
                    f"{np.rad2deg(np.linalg.norm(tol)):.2g} deg): a frozen reference (a tracker holding its last "
                    "attitude). Mark those rows valid = 0, or cut the maneuver there",
                    where=f"star_tracker.csv:{lines[r0]}-{lines[r1]}")


def _runs_rows(quat):
    """(first, last) rows of each stretch over which ``quat`` repeats exactly (two rows or more)."""
    same = np.concatenate([[False], (quat[1:] == quat[:-1]).all(axis=1), [False]])
    edges = np.flatnonzero(np.diff(same.astype(int)))
    return [(int(s), int(e)) for s, e in zip(edges[::2], edges[1::2])]


def _spikes(campaign, windows, sf_bound, findings):
    lines, time = campaign.lines["gyro.csv"], campaign.gyro_time
    n_tests = sum(w.g_rows.size for w in windows) * len(campaign.channels)
    z = max(DETECTION_SD, float(-ndtri(SPIKE_FALSE_ALARMS / (2 * max(n_tests, 1)))))
    shown, mild = 0, []
    for w in windows:
        rows = w.g_rows[1:-1]
        rows = rows[rows >= 3]
        rows = rows[rows < len(time) - 3]
        if not rows.size:
            continue
        rate = np.linalg.norm(w.d_st, axis=1) / np.diff(w.st_time)
        k = np.clip(np.searchsorted(w.st_time, time[rows]) - 1, 0, len(rate) - 1)
        near = np.max([rate[np.clip(k + j, 0, len(rate) - 1)] for j in (-1, 0, 1)], axis=0)
        dt = time[rows] - time[rows - 1]
        rate_noise = np.sqrt(2.0) * w.sigma_st / w.dt_st
        for c, channel in enumerate(campaign.channels):
            x = campaign.gyro_columns[channel.name]
            neighbours = np.median(np.stack([x[rows + j] for j in (-3, -2, -1, 1, 2, 3)]), axis=0)
            with np.errstate(over="ignore", invalid="ignore"):
                jump = np.abs(x[rows] - neighbours)
            allowed = (1 + sf_bound) * 2 * near * dt + z * (w.sigma_inc[c] * np.sqrt(1.5) + rate_noise * dt)
            for i in np.flatnonzero(~(jump <= allowed)):
                row, value, typical = rows[i], x[rows[i]], neighbours[i]
                if jump[i] <= SPIKE_REFUSAL_FACTOR * allowed[i]:
                    mild.append(f"{lines[row]} ('{channel.name}', {value:.3g} rad against about {typical:.3g})")
                    continue
                shown += 1
                if shown > 5:
                    continue
                ratio = abs(value / typical) if typical else np.inf
                decade = np.log10(ratio) if np.isfinite(ratio) and ratio > 0 else np.nan
                cause = (f"a cell that lost its exponent ({ratio:.3g} times its neighbours, about 1e{round(decade)})"
                         if np.isfinite(decade) and decade >= 2 and abs(decade - round(decade)) < 0.3 else
                         "a corrupt cell")
                findings.refuse(
                    "spike",
                    f"gyro.csv, line {lines[row]}, column '{channel.name}': {value:.6g} rad, where its neighbours read "
                    f"about {typical:.3g} rad and the reference's motion allows a change of at most {allowed[i]:.2g} "
                    f"rad (maneuver {w.m.id}, t = {time[row]:.6g} s): {cause}. Correct the value, or remove the row",
                    where=f"gyro.csv:{lines[row]}:{channel.name}")
    if shown > 5:
        findings.refuse("spike", f"gyro.csv: {shown - 5} more single cells beyond what the reference's motion allows")
    if mild:
        findings.warn("spike", f"gyro.csv: {len(mild)} single cell(s) leave their neighbours by more than the reference's "
                      f"motion allows, but by less than {SPIKE_REFUSAL_FACTOR:g} times it (a jerk or a glitch, kept): "
                      f"lines {', '.join(mild[:5])}{' ...' if len(mild) > 5 else ''}")

