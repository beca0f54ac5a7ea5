"""Where a recording rests, read off its gyro, and the maneuvers it splits into there.

A lab recording often rests between its motions (BROAD: 30 s, two minutes of motion, 30 s). The
gyro tells the rests without any label: at rest it reads its bias and its noise, in motion far
more. The noise at rest is measured in the recording itself: its samples are cut into blocks of
`REST_BLOCK_S`, and the quietest `QUIETEST_SHARE` of the blocks (the smallest spread over the
three channels) give each channel's sd (their median block sd) and bias (their median mean).
A sample is at rest where the rate less that bias, averaged over `SMOOTH_S` (which shrinks the
noise by the square root of the samples averaged), has a norm below `REST_SIGMAS` times what
the noise leaves in that average; a rest is a run of such samples at least ``min_rest_s`` long
(`MIN_REST_S` unless the mapping says otherwise).

A file is cut in the middle of each rest that neither opens nor closes it, so that every
maneuver keeps half a rest on either side (its bias is seen still); a file with no such rest is
one maneuver."""

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = [
    "ARW_AVERAGE_S", "MIN_REFERENCE_PAIRS", "MIN_REST_S", "QUIETEST_SHARE", "REFERENCE_NOISE_FLOOR_RAD", "REST_BLOCK_S",
    "REST_SIGMAS", "SMOOTH_S", "WHITE_DIFFERENCE_LAG1_MAX", "ReferenceAtRest", "Rests", "arw_at_rest", "find_rests",
    "pieces", "pooled_reference_noise", "reference_noise_at_rest",
]

REST_BLOCK_S = 0.5
"""The blocks the noise at rest is measured over."""
QUIETEST_SHARE = 0.1
"""The share of the blocks, the quietest, that measure the noise at rest: a file at rest for at
least half of that (5 % of its length) measures it from rest alone (the median of their spreads)."""
SMOOTH_S = 0.1
"""The rate is averaged over this long before it is compared with the threshold."""
REST_SIGMAS = 5.0
"""The threshold, in sds of the averaged rate's norm at rest: a sample at rest exceeds it with
probability about 1e-5 (three channels of white noise); the slowest motion taken for rest
is a few times the noise's own sd, a tenth or two of a deg/s for a MEMS gyro."""
MIN_REST_S = 2.0
"""The shortest rest a file is cut at (a pause in a hand-held motion is shorter)."""


@dataclass
class Rests:
    """What `find_rests` found in one file (rows counted from 0, ends exclusive)."""

    runs: list
    """[(first row, row after the last)] of each rest."""
    sigma: np.ndarray
    """(n_channels,) each channel's noise sd at rest, in the rate's unit (rad/s)."""
    bias: np.ndarray
    """(n_channels,) each channel's rate at rest."""
    threshold: float
    """The averaged rate's norm below which a sample is at rest."""
    smooth: int
    """The samples averaged."""
    arw_rad_sqrt_s: float | None = None
    """The angle random walk the rests show (`arw_at_rest`; None where they are too short to tell)."""


def find_rests(rate: np.ndarray, step_s: float, min_rest_s: float = MIN_REST_S) -> Rests:
    """The rests of one recording from its gyro rates ``rate`` (N, n_channels; rad/s) sampled every
    ``step_s`` seconds."""
    rate = np.asarray(rate, dtype=float)
    n = len(rate)
    block = max(2, round(REST_BLOCK_S / step_s))
    count = max(1, n // block)
    blocks = rate[:count * block].reshape(count, min(block, n), rate.shape[1])
    spread = blocks.std(axis=1, ddof=1)
    quiet = np.argsort(np.linalg.norm(spread, axis=1))[:max(1, int(np.ceil(QUIETEST_SHARE * count)))]
    sigma = np.median(spread[quiet], axis=0)
    bias = np.median(blocks[quiet].mean(axis=1), axis=0)
    smooth = max(1, round(SMOOTH_S / step_s))
    threshold = float(REST_SIGMAS * np.linalg.norm(sigma) / np.sqrt(smooth))
    averaged = _moving_mean(rate - bias, smooth)
    still = np.linalg.norm(averaged, axis=1) < threshold
    shortest = max(1, round(min_rest_s / step_s))
    runs = [(a, b) for a, b in _runs(still) if b - a >= shortest]
    return Rests(runs, sigma, bias, threshold, smooth, arw_at_rest(rate, step_s, runs))


def pieces(n: int, runs) -> list:
    """The maneuvers ``[(first row, row after the last)]`` of a file of ``n`` rows with rests
    ``runs``: cut in the middle of every rest that neither opens nor closes the file."""
    cuts = [(a + b) // 2 for a, b in runs if a > 0 and b < n]
    edges = [0, *cuts, n]
    return [(a, b) for a, b in itertools.pairwise(edges) if b > a]


def windows(spans, step_s: float, window_s) -> list:
    """Each span ``(first row, row after the last)`` cut into windows of about ``window_s`` seconds
    (``round(length / window_s)`` equal pieces, at least one; None or 0: the spans as they are). Each
    window becomes a maneuver with its own anchor attitude and bias (the MOM model's per-maneuver terms):
    an error that wanders slowly over a long free motion (a MEMS bias's instability, a slow drift of
    the reference) then cannot pile up into an attitude error the white noise model cannot carry."""
    if not window_s:
        return list(spans)
    out = []
    for a, b in spans:
        n = max(1, round((b - a) * step_s / window_s))
        edges = np.linspace(a, b, n + 1).round().astype(int)
        out.extend((int(lo), int(hi)) for lo, hi in itertools.pairwise(edges) if hi > lo)
    return out


def _moving_mean(x: np.ndarray, k: int) -> np.ndarray:
    """The mean of each row's ``k`` neighbours centred on it (fewer at the ends)."""
    if k <= 1:
        return x
    total = np.vstack([np.zeros((1, x.shape[1])), np.cumsum(x, axis=0)])
    rows = np.arange(len(x))
    lo = np.clip(rows - k // 2, 0, len(x))
    hi = np.clip(rows - k // 2 + k, 0, len(x))
    return (total[hi] - total[lo]) / (hi - lo)[:, None]


def _runs(mask: np.ndarray) -> list:
    """``[(start, end)]`` of each run of True in ``mask`` (end exclusive)."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


ARW_AVERAGE_S = 1.0
"""The averaging time of the ARW measured at rest (`arw_at_rest`): at 1 s the Allan deviation of white
rate noise equals the ARW coefficient, before bias instability shows (tens of seconds for MEMS)."""


def arw_at_rest(rate: np.ndarray, step_s: float, runs) -> float | None:
    """The angle random walk (rad/sqrt(s)) the rests show, the largest channel's: the sd of the rate's
    `ARW_AVERAGE_S` means within the rests ``runs`` (`Rests.runs`), times the square root of that time (the Allan deviation at
    1 s, non-overlapping); None where the rests hold fewer than ten such means. A band-limited MEMS output
    has correlated samples, so its per-sample sd times sqrt(dt) would understate the walk."""
    k = max(1, round(ARW_AVERAGE_S / step_s))
    steps = []
    for a, b in runs:
        n = (b - a) // k
        if n > 1:
            means = rate[a:a + n * k].reshape(n, k, -1).mean(axis=1)
            steps.append(np.diff(means, axis=0))
    if sum(len(d) for d in steps) < 10:
        return None
    allan = np.sqrt(0.5 * np.mean(np.concatenate(steps) ** 2, axis=0))
    return float(np.max(allan) * np.sqrt(k * step_s))


MIN_REFERENCE_PAIRS = 200
"""The fewest pairs of consecutive reference samples within the rests that state the reference's noise
at rest (`reference_noise_at_rest`): the sd of 200 is known to 5 %, within the noise check's band."""

REFERENCE_NOISE_FLOOR_RAD = 1e-8
"""Below this sd (0.002 arcsec) a reference at rest repeats its value to rounding: it states no noise."""

WHITE_DIFFERENCE_LAG1_MAX = -0.35
"""The differences of white samples correlate -0.5 with their neighbours (each shares one sample, with
the opposite sign); where they correlate more than this (pooled, 200 pairs: -0.5 within about 0.05), the
reference's error is correlated over the interval kept (a motion-capture system resampled above its
cameras' rate), its differences understate its noise, and the rests state none."""


@dataclass
class ReferenceAtRest:
    """The reference's noise in one recording's rests (`reference_noise_at_rest`)."""

    cross_rad: float
    """Its sd about each of the two axes across the boresight."""
    about_rad: float
    """Its sd about the boresight."""
    pairs: int
    """The pairs of consecutive kept samples it rests on."""
    lag1: float
    """The correlation of each difference with the next (-0.5 for white samples)."""

    @property
    def white(self) -> bool:
        """Whether it states the reference's white noise: differences as white samples give
        (`WHITE_DIFFERENCE_LAG1_MAX`) and above `REFERENCE_NOISE_FLOOR_RAD`."""
        return self.lag1 <= WHITE_DIFFERENCE_LAG1_MAX and min(self.cross_rad, self.about_rad) >= REFERENCE_NOISE_FLOOR_RAD


def reference_noise_at_rest(quat, kept, runs, boresight_body) -> ReferenceAtRest | None:
    """The reference's noise at rest: its sd about each of the two axes across ``boresight_body`` and
    about it, from the rotations between consecutive kept samples (``kept``: the rows the campaign keeps,
    valid) within the rests ``runs`` (`Rests.runs`), where the body does not turn, so each rotation is the
    difference of two samples' errors: its variance twice theirs. In the reference's own axes, the body's
    where its mounting is estimated (a declared mounting turns the split). Mean squares, as the noise
    model's variance takes them (a sample's rare large error counts as the likelihood counts it).
    ``quat`` (N, 4) scalar last. A sample that repeats the one before to the bit is a held frame (a
    motion-capture system that lost its markers and holds its last pose), no measurement: it is left out,
    so that a frozen stretch does not read as a quiet reference. None where the rests hold fewer than
    `MIN_REFERENCE_PAIRS` pairs; where
    the differences are not those of white samples (`ReferenceAtRest.white`), what they show is kept for
    the report, not stated. What an at-rest recording states for the reference, as `arw_at_rest` does
    for the gyro."""
    b = np.asarray(boresight_body, dtype=float)
    b = b / np.linalg.norm(b)
    steps = []
    for a, z in runs:
        rows = a + np.flatnonzero(kept[a:z])
        rows = rows[np.r_[True, np.any(np.diff(quat[rows], axis=0) != 0.0, axis=1)]] if len(rows) else rows
        if len(rows) > 1:
            r = Rotation.from_quat(quat[rows])
            turned = (r[:-1].inv() * r[1:]).as_rotvec()
            steps.append(turned - turned.mean(axis=0))  # a rest that creeps (a body settling) is not noise
    if sum(len(d) for d in steps) < MIN_REFERENCE_PAIRS:
        return None
    d = np.concatenate(steps)
    about_sq = (d @ b) ** 2
    cross_sq = np.sum(d**2, axis=1) - about_sq
    next_product = sum(float(np.sum(x[:-1] * x[1:])) for x in steps)
    lag1 = next_product / float(np.sum(d**2)) if np.sum(d**2) > 0 else 0.0
    return ReferenceAtRest(float(np.sqrt(np.mean(cross_sq) / 4.0)), float(np.sqrt(np.mean(about_sq) / 2.0)),
                           len(d), lag1)


def pooled_reference_noise(found) -> tuple:
    """The reference noise (cross, about; rad) several recordings' rests state together: their mean
    squares weighted by their pairs, the likelihood's estimate of one level, over those whose
    differences are white (`ReferenceAtRest.white`); None where none is."""
    usable = [f for f in found if f is not None and f.white]
    if not usable:
        return None
    pairs = np.array([f.pairs for f in usable], dtype=float)
    cross = np.sqrt(np.sum(pairs * np.array([f.cross_rad for f in usable]) ** 2) / pairs.sum())
    about = np.sqrt(np.sum(pairs * np.array([f.about_rad for f in usable]) ** 2) / pairs.sum())
    return float(cross), float(about)
