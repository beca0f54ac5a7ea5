"""Does a gyro clip at its range? Told from the gyro alone, whatever the reference does.

A gyro that reaches its range reports the range, not the rate: its output sits flat at its
peak while the body turns faster. Two things give that away on the gyro side, with no
reference at all:

- the channel's rate sits within a small band of the largest rate it reports (or of the range
  a mapping declares) for several samples in a row, and
- there it is smoother than the channel's own noise, both measured by second differences: a
  saturated converter outputs one value, or one that drifts slowly as its calibration mixes in
  the other axes, while a body that really turns at a steady rate (a spacecraft's coast at its
  slew rate) still shows the sensor's noise at the top, and a smooth peak of a hand-held motion
  shows its changing curvature and the noise.

A declared range needs no flatness: a rate that sits at the range for a few samples is at
the range, and what the body did beyond it is not measured. A gyro too smooth to be judged alone
(no noise at all), and as a second test wherever the reference is dense enough: the reference's
own rotation shows it, as where the gyro sits near its peak the reference turns faster than the
gyro says (`reference_evidence`).

The channel's noise is measured over all of it, motion included (`channel_noise`): on hand-held
recordings the changing acceleration makes up most of it (0.52 deg/s on RepoIMU's Test05, whose
quiet stretches show 0.045), so "flat" means smoother than the rest of the channel. What that
cannot tell from a clip: a gyro that coasts at a truly steady rate with a noise under a quarter of
the rest of its motion's roughness, as a noise-free simulation with smooth slews elsewhere, or a
quiet coast between violent shaking. Declare the range (``gyro.range_deg_s``), which replaces the
judgement by a comparison, or give the simulation its sensor's noise.
"""

from dataclasses import dataclass

import numpy as np

from gyrocal.checks.sensing import Sensed
from gyrocal.finding import Findings
from gyrocal.inference.fit.identification import DETECTION_SD
from gyrocal.model.units import AXES

__all__ = [
    "BAND_NOISE", "DECLARED_MIN_RUN", "FLAT_BAND", "FLAT_NOISE", "LEVEL_NOISE", "MIN_RUN", "MIN_SECOND_DIFFERENCES",
    "QUIET_SHARE", "REFERENCE_BAND", "Plateau", "channel_noise", "gyro_range_rad_s", "plateaus", "reference_evidence",
    "saturation_findings",
]

FLAT_BAND = 0.01
"""A sample is near the peak when its rate is within this share of the peak (or of the declared
range). A clipped Xsens channel's output drifts 0.3 % along its plateau, as its calibration
mixes in the other axes."""
BAND_NOISE = 8.0
"""...or within this many noise sds of it, where that is wider: the peak of a steady rate is the
top of its noise, so the band must hold the noise's whole spread, or it would keep only its
upper tail, in short runs that are narrow by construction."""
MIN_RUN = 8
"""Consecutive samples near the observed peak that make a run ("several in a row"); the runs are
judged together, so a few lucky short runs of noise do not make a channel flat."""
MIN_SECOND_DIFFERENCES = 14
"""Without a declared range, the runs near a peak are judged only where they hold this many second
differences together: white noise at a steady rate then reads flat (`FLAT_NOISE`) by chance in
0.07 % of peaks (in 1.2 % with one run of 8 samples, 6 second differences; simulated). The shortest
clipped stretch of the real recordings below holds 16 (RepoIMU Test06 Trial2, 18 samples at -408 deg/s)."""
DECLARED_MIN_RUN = 2
"""Consecutive samples at a declared range that make it clipped: two samples at the range are a
flat top, whatever their noise."""
FLAT_NOISE = 0.25
"""The runs near a peak are flat when their own noise sd, measured as `channel_noise` measures the
channel's (second differences, pooled over the runs), is below this share of the channel's. White
noise at a steady rate gives 1 whatever filtered it (a trapezoid's average included), as both sides
are the same statistic (the quantised simulated DTGs of tests/data/tiny.yaml and
config/scenarios/mom.yaml: 1.0). On the trapezoid-integrated rates of every RepoIMU and BROAD recording the
runs that do not clip give 0.47 to 2.8, and those at an Xsens's range (408-426 deg/s: Test05's three
trials, Test06 Trials 1 and 2, Test07 Trials 2 and 3) 0.024 to 0.115: its output drifts smoothly
along the plateau. (The median change between samples, the test before, gave 0.08 to 0.76 on the
clipped runs and 0.78 on one that does not clip: it let four clipped trials through.)"""
LEVEL_NOISE = 10.0
"""A peak is judged only where it stands this many noise sds clear of zero: on an axis that
barely turns, the "peak" is noise."""
REFERENCE_BAND = 0.05
"""The reference-based test compares the sensors where the gyro is within this share of its peak."""
QUIET_SHARE = 0.5
"""Without a known range, the reference-based test judges only the axes whose peak rate is at least
this share of the maneuver's fastest axis: a gyro clips at its range, never at the peak of a quiet
stretch (an axis another of the same gyros outruns has not reached the range)."""


def gyro_range_rad_s(campaign):
    """The gyros' range (rad/s) as the campaign knows it, one number or one per channel name, or
    None: ``campaign.yaml``'s ``gyro.range_deg_s``. The one place the checks read it (a sensor
    class's range would be added here)."""
    declared = (campaign.gyro or {}).get("range_deg_s")
    return None if declared is None else float(np.deg2rad(declared))


@dataclass(frozen=True)
class Plateau:
    """Where one channel sits flat at its peak of one sign, or at a declared range."""

    channel: str
    sign: int
    """+1 at the positive peak, -1 at the negative one."""
    level_rad_s: float
    """The peak rate (or the declared range) it sits at, as a magnitude."""
    declared: bool
    """Whether ``level_rad_s`` is the range the campaign declares."""
    samples: int
    """Samples within the band of the level: what the gyro did not measure."""
    flat_runs: int
    """Runs of at least `MIN_RUN` (`DECLARED_MIN_RUN` at a declared range) that sit flat there."""
    first: int
    """Index of the first sample within the band, in the maneuver's increments."""
    roughness_rad_s: float
    """The runs' own noise sd, from their second differences as `channel_noise` (pooled over the runs)."""
    noise_rad_s: float
    """The channel's noise sd (`channel_noise`)."""


def channel_noise(rate, skip=None) -> float:
    """A robust noise sd of one channel's sampled rate, from its second differences (1.4826 times
    their median absolute value over sqrt(6), the sd of a white sequence's second difference): a
    steady rate and a constant acceleration cancel, so holds, coasts and ramps all show the
    sensor's noise. A hand-held motion's changing acceleration adds to it (0.52 deg/s on the fast
    RepoIMU trial's x gyro, 0.13 on the slower trials, whose rates the trapezoid averages), which
    makes the flatness test looser (the module's docstring says what that cannot tell). ``skip``:
    samples left out (the near-peak ones, where a clipped gyro has no noise), unless too few would be
    left. Zero for a noise-free or coarsely quantised gyro at rest or on constant accelerations, which
    cannot be judged flat."""
    d2 = np.abs(np.diff(rate, 2))
    if skip is not None and (~skip[1:-1]).sum() >= 2 * MIN_RUN:
        d2 = d2[~skip[1:-1]]
    return _second_difference_sd(d2)


def _second_difference_sd(d2) -> float:
    """A white sequence's robust sd from its absolute second differences ``d2``: 1.4826 times their median
    over sqrt(6), the sd of a white sequence's second difference (0 where there are none)."""
    return float(1.4826 * np.median(d2) / np.sqrt(6.0)) if d2.size else 0.0


def _runs(mask) -> list:
    """``(start, stop)`` of each run of consecutive True in ``mask``."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def plateaus(name: str, rate, range_rad_s=None) -> list:
    """The flat tops of one channel's rate (rad/s, one value per sample), one `Plateau` per sign
    that has one. At a declared ``range_rad_s``: `DECLARED_MIN_RUN` samples in a row within
    `FLAT_BAND` of it, flat or not. Otherwise, at the largest rate observed: the runs of at least
    `MIN_RUN` samples within the band of it, `MIN_SECOND_DIFFERENCES` second differences together,
    whose own noise (`channel_noise` of the runs, pooled: one test per sign, however many runs) is less
    than `FLAT_NOISE` of the channel's."""
    rate = np.asarray(rate, dtype=float)
    if len(rate) < MIN_RUN:
        return []
    top = np.maximum(rate.max(), 0.0)
    bottom = np.minimum(rate.min(), 0.0)
    noise = channel_noise(rate, (rate >= (1 - FLAT_BAND) * top) | (rate <= (1 - FLAT_BAND) * bottom))
    found = []
    for sign in (1, -1):
        x = sign * rate
        peak = float(x.max())
        if range_rad_s is not None and peak >= (1 - FLAT_BAND) * range_rad_s:
            near = x >= (1 - FLAT_BAND) * range_rad_s
            spans = [(a, b) for a, b in _runs(near) if b - a >= DECLARED_MIN_RUN]
            if spans:
                found.append(_plateau(name, sign, float(range_rad_s), True, x, spans, noise))
                continue
        if noise == 0 or peak < LEVEL_NOISE * noise or range_rad_s is not None:
            continue  # with a known range, only the range: a peak below it is no clipping
        near = x >= peak - max(FLAT_BAND * peak, BAND_NOISE * noise)
        spans = [(a, b) for a, b in _runs(near) if b - a >= MIN_RUN]
        if sum(b - a - 2 for a, b in spans) >= MIN_SECOND_DIFFERENCES:
            p = _plateau(name, sign, peak, False, x, spans, noise)
            if p.roughness_rad_s < FLAT_NOISE * noise:
                found.append(p)
    return found


def _plateau(name, sign, level, declared, x, spans, noise) -> Plateau:
    """The `Plateau` of the flat ``spans`` at ``level``; its samples are those within `FLAT_BAND`
    of the level (the runs may reach further down, into the noise's spread)."""
    d2 = np.concatenate([np.abs(np.diff(x[a:b], 2)) for a, b in spans])
    at = x >= (1 - FLAT_BAND) * level
    return Plateau(name, sign, level, declared, int(at.sum()), len(spans), int(np.argmax(at)),
                   _second_difference_sd(d2), noise)


def saturation_findings(sensed: Sensed, sf_bound, findings: Findings, range_rad_s=None) -> bool:
    """Whether a gyro channel of this maneuver clips at its range; if so, one refusal says which
    channel, how many samples, at what rate, in which maneuver and what to do. Every raw channel
    of the maneuver is judged, redundant ones included, from its own rate (`plateaus`), whatever
    the reference does; that is done once, with the in-loop channel set's ``sensed`` (a ``sensed``
    of another set, ``sensed.set_index > 0``, skips it). Then, for a gyro too smooth to be judged
    alone, the reference's rotation where the set's gyros sit near their peak
    (`reference_evidence`). ``range_rad_s``: the gyro's declared range (rad/s), one number or one
    per channel name. A clipped maneuver is refused, never fitted silently."""
    data = sensed.data
    if getattr(sensed, "set_index", 0) == 0:
        rate = data.increments / data.dt[:, None]
        for i, c in enumerate(data.channels):
            declared = range_rad_s.get(c.name) if isinstance(range_rad_s, dict) else range_rad_s
            found = plateaus(c.name, rate[:, i], declared)
            if found:
                findings.refuse("saturation", _why(data, c.name, found))
                return True
    return reference_evidence(sensed, sf_bound, findings, range_rad_s)


def _why(data, channel: str, found: list) -> str:
    """The refusal of a channel's `Plateau`s (one per sign)."""
    parts = []
    for p in found:
        what = "at its declared range" if p.declared else "flat at its peak"
        runs = DECLARED_MIN_RUN if p.declared else MIN_RUN
        parts.append(f"{what} {p.sign * np.rad2deg(p.level_rad_s):+.4g} deg/s for {p.samples} samples "
                     f"(within {FLAT_BAND:.0%}; {p.flat_runs} run{'s' if p.flat_runs > 1 else ''} of {runs} or more)")
    judged = [p for p in found if not p.declared]
    flat = (f", its noise there {np.rad2deg(judged[0].roughness_rad_s):.2g} deg/s where the channel's is "
            f"{np.rad2deg(judged[0].noise_rad_s):.2g} deg/s" if judged else "")
    t_first = float(data.gyro_time[min(p.first for p in found)])
    return (f"maneuver {data.id}: gyro channel {channel} sits {' and '.join(parts)}{flat}: the gyro "
            f"clips at its range, so the body's rotation there is not measured. Leave the maneuver out, or cut it "
            f"before the first clipped sample, at {t_first:.2f} s")


def reference_evidence(sensed: Sensed, sf_bound, findings: Findings, range_rad_s=None) -> bool:
    """A gyro that reaches its range clips: where its rate sits near its peak, the reference turns
    faster than the gyro says, in the gyro's direction, by more than any scale error and more
    than `DETECTION_SD` times the noise of as many independent reference intervals (on an axis
    that barely turns, the "peak" is noise; conservative, since over consecutive intervals the
    reference's noise partly cancels). Needs a reference dense enough to resolve the clipped
    stretch; it is the only test of a noise-free gyro. Only an axis whose peak can be the range is
    judged: with ``range_rad_s`` (one number, or one per channel name), one within `REFERENCE_BAND`
    of it; without, one at least `QUIET_SHARE` of the fastest axis's peak. Returns whether it clipped."""
    data = sensed.data
    rate = np.abs(sensed.body / data.dt[:, None])
    at_st = rate[data.st_interval()[0][1:]]
    sets = getattr(data, "sets", None)
    fastest = rate.max()
    for a in range(3):
        peak = rate[:, a].max()
        if isinstance(range_rad_s, dict):
            limit = range_rad_s.get(sets[getattr(sensed, "set_index", 0)][a]) if sets else None
        else:
            limit = range_rad_s
        if peak < ((1 - REFERENCE_BAND) * limit if limit is not None else QUIET_SHARE * fastest):
            continue
        near = at_st[:, a] >= (1 - REFERENCE_BAND) * peak
        turned_gyro = np.abs(sensed.d_gyro[near, a]).sum()
        if near.sum() < 5 or turned_gyro == 0:
            continue
        turned_st = np.sum(np.sign(sensed.d_gyro[near, a]) * sensed.d_st[near, a])
        noise = 1.4826 * np.median(np.abs(np.diff(sensed.d_st[:, a]))) / np.sqrt(2)
        excess = turned_st / turned_gyro
        shortfall = turned_st - (1 + 2 * sf_bound) * turned_gyro
        if shortfall > DETECTION_SD * noise * np.sqrt(near.sum()):
            clipped = int((rate[:, a] >= (1 - REFERENCE_BAND) * peak).sum())
            channel = f" (channel {sets[getattr(sensed, 'set_index', 0)][a]})" if sets else ""
            findings.refuse("saturation",
                f"maneuver {data.id}: {clipped} gyro samples about {AXES[a]}{channel} sit within {REFERENCE_BAND:.0%} of the "
                f"peak rate {np.rad2deg(peak):.1f} deg/s, where the reference turns {excess:.3f} times as fast: the "
                "gyro clips at its range, so its rotation there is not measured. Leave the maneuver out, or cut it "
                "before the first clipped sample")
            return True
    return False
