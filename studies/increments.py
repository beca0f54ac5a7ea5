"""Which noise a real trial's misfit is (issue 42), read off the gyro's increments against the
reference's over a lag, outside the pipeline: a BROAD trial (``.mat``) or a RepoIMU one (``.csv``).
Over a lag ``L`` the reference's relative rotation
``R(t)^T R(t + L)`` minus the gyro's increment (corrected by one 3x3 response, a bias and a latency,
fitted once) has three signatures:

- white reference noise: flat in ``L`` (about sqrt(2) times the reference's sigma);
- a white error on the gyro's rate (ARW, or a rate-proportional scale-factor noise): grows as sqrt(L);
- a systematic rate error (a scale-factor nonlinearity, a bias that changes with the motion): grows as L.

Binned by the mean rate over the lag, the growth with ``|omega|`` tells a gyro or reference term that
follows the motion from one that does not. At rest the same numbers give the ARW and the reference
noise a data sheet or an at-rest recording would.

``--explain`` then asks which candidate takes the 0.1-s increment error in motion, each fitted by
least squares on top of the global fit: a timing offset, a bias or a scale factor that wander from
one 1-s window to the next (a clock offset between the two systems, a bias that follows the motion);
a response to the angular acceleration, to ``omega_i omega_j`` (flex of the marker body, a
centripetal load); and how much of the error lies along the rotation axis (a third if isotropic, all
of it for a timing error).

    python studies/increments.py ../shared/data/broad/01_undisturbed_slow_rotation_A.mat \
        [--figure docs/real-data/broad_increments.png] [--explain] [--write-flagged DIR]
"""

import argparse
from pathlib import Path

import numpy as np
from scipy.io import loadmat
from scipy.optimize import least_squares
from scipy.signal import savgol_filter
from scipy.spatial.transform import Rotation

from gyrocal.model.units import ARCSEC_RAD

LAGS = (3, 29, 286, 858, 2860)
"""Lags in samples (0.01 s to 10 s at 285.7 Hz)."""
RATE_BINS_RAD_S = (0.0, 0.05, 0.5, 1.0, 2.0, 3.0, 5.0, 20.0)
"""Mean |omega| bins: the first is rest."""


EXPLAIN_LAG = 29
"""The lag (samples) of ``--explain``: 0.1 s at BROAD's rate, 0.29 s at RepoIMU's."""
EXPLAIN_WINDOW_S = 1.0
"""The window over which a wandering term is held constant."""
MOVING_RAD_S = 0.3
"""|omega| above which a lag counts as in motion."""


def load(path: Path):
    """Rates (N, 3) rad/s, reference quaternions (N, 4) scalar last, their validity, the sample step:
    a BROAD ``.mat`` or a RepoIMU ``.csv`` (time; Vicon W, X, Y, Z; acceleration; gyro; magnetometer,
    all-zero quaternions where the reference has none)."""
    if path.suffix == ".csv":
        data = np.loadtxt(path, delimiter=";", skiprows=2, usecols=range(11))
        q = data[:, [2, 3, 4, 1]]
        return data[:, 8:11], q, np.linalg.norm(q, axis=1) > 0.5, float(np.median(np.diff(data[:, 0])))
    m = loadmat(path)
    q = np.asarray(m["opt_quat"], float)[:, [1, 2, 3, 0]]
    return np.asarray(m["imu_gyr"], float), q, np.all(np.isfinite(q), axis=1), 1.0 / float(np.squeeze(m["sampling_rate"]))


def specific_force(path: Path) -> np.ndarray:
    """The accelerometer's specific force (N, 3), m/s^2, of a trial `load` reads."""
    if path.suffix == ".csv":
        return np.loadtxt(path, delimiter=";", skiprows=2, usecols=range(8))[:, 5:8]
    return np.asarray(loadmat(path)["imu_acc"], float)


def corrected_rate(rate, step_s, response, bias_rad_s, latency_s):
    """The gyro's rate corrected: ``response @ (rate(t + latency) - bias)``, rad/s."""
    t = np.arange(len(rate)) * step_s
    shifted = np.stack([np.interp(t + latency_s, t, rate[:, i]) for i in range(3)], axis=1)
    return (shifted - bias_rad_s) @ np.asarray(response).T


def increments(rate, quat, valid, step_s, lag, corrected, stride):
    """Per lag starting at ``starts`` (both ends valid, one every ``stride`` samples): the gyro's
    increment (trapezoid, as `gyrocal import` makes it) and the reference's, as Rotations."""
    inc = 0.5 * (corrected[1:] + corrected[:-1]) * step_s
    starts = np.arange(0, len(rate) - lag - 1, stride)
    starts = starts[valid[starts] & valid[starts + lag]]
    gyro = Rotation.identity(len(starts))
    for j in range(lag):
        gyro = gyro * Rotation.from_rotvec(inc[starts + j])
    return starts, gyro, Rotation.from_quat(quat[starts]).inv() * Rotation.from_quat(quat[starts + lag])


def lag_errors(rate, quat, valid, step_s, lag, response, bias_rad_s, latency_s, stride=None):
    """Rotation-vector errors (rad) of the gyro's increment over ``lag`` samples against the reference's,
    the gyro corrected (`corrected_rate`), and the mean |rate| over each lag; one lag every ``stride``
    samples."""
    corrected = corrected_rate(rate, step_s, response, bias_rad_s, latency_s)
    starts, gyro, ref = increments(rate, quat, valid, step_s, lag, corrected, stride or lag)
    speed = np.linalg.norm(rate, axis=1)
    total = np.concatenate([[0.0], np.cumsum(speed)])
    mean_rate = (total[starts + lag + 1] - total[starts]) / (lag + 1)
    return (gyro.inv() * ref).as_rotvec(), mean_rate


def _response_regressors(ref: Rotation, at_start: np.ndarray, at_end: np.ndarray) -> np.ndarray:
    """(n, 3, 9): the increment error of a reference error ``K x(t)`` with one 3x3 ``K``, ``x`` taken
    at the lag's two ends: ``R_inc K x(t + L) - K x(t)``, ``R_inc`` the reference's increment."""
    n = len(at_start)
    cells = np.zeros((9, n, 3, 3))
    cells[np.arange(9), :, np.arange(9) // 3, np.arange(9) % 3] = 1.0
    end = np.einsum("knij,nj->kni", cells, at_end)
    start = np.einsum("knij,nj->kni", cells, at_start)
    return np.einsum("nij,knj->nik", ref.as_matrix(), end) - start.transpose(1, 2, 0)


def _left(error: np.ndarray, regressors: np.ndarray, groups: np.ndarray) -> float:
    """RMS per axis (arcsec) of ``error`` (n, 3) after least squares on ``regressors`` (n, 3, k),
    fitted apart within each group."""
    left = []
    for g in np.unique(groups):
        sel = groups == g
        a, b = regressors[sel].reshape(sel.sum() * 3, -1), error[sel].ravel()
        left.append(b - a @ np.linalg.lstsq(a, b, rcond=None)[0] if a.size else b)
    return float(np.sqrt(np.mean(np.concatenate(left) ** 2)) / ARCSEC_RAD)


GLITCH_OFF = 0.5
"""A one-sample reference step counts as a glitch where its part along the gyro's step is off the
gyro's by more than this fraction (a frame taken late, then the next catching up)."""


def glitch_frames(rate, quat, valid, step_s, corrected):
    """The reference's timing glitches in motion: per sample, whether it ends a glitched one-sample
    step; the glitched steps' count, the moving steps' count, and their share of the one-sample error's
    variance along the rotation axis."""
    starts, gyro, ref = increments(rate, quat, valid, step_s, 1, corrected, 1)
    g, r = gyro.as_rotvec(), ref.as_rotvec()
    moving = np.linalg.norm(corrected[starts], axis=1) > MOVING_RAD_S
    size = np.maximum(np.sum(g ** 2, axis=1), 1e-30)
    ratio = np.sum(r * g, axis=1) / size
    glitch = moving & (np.abs(ratio - 1.0) > GLITCH_OFF)
    along_sq = (ratio - 1.0) ** 2 * size
    frames = np.zeros(len(rate), bool)
    frames[starts[glitch]] = frames[starts[glitch] + 1] = True
    return frames, int(glitch.sum()), int(moving.sum()), float(along_sq[glitch].sum() / along_sq[moving].sum())


def glitches(rate, quat, valid, step_s, corrected, lag=EXPLAIN_LAG):
    """`glitch_frames`' counts and share, and the error over ``lag`` (RMS per axis, arcsec) in motion
    with and without the lags that end on a glitch's frames."""
    frames, n, moving, share = glitch_frames(rate, quat, valid, step_s, corrected)
    s, gl, rl = increments(rate, quat, valid, step_s, lag, corrected, 3)
    error = (gl.inv() * rl).as_rotvec()
    in_motion = np.linalg.norm(corrected[s], axis=1) > MOVING_RAD_S
    clean = in_motion & ~frames[s] & ~frames[s + lag]
    rms = lambda sel: float(np.sqrt(np.mean(error[sel] ** 2)) / ARCSEC_RAD)
    return n, moving, share, rms(in_motion), rms(clean)


def write_flagged(source: Path, frames: np.ndarray, out: Path):
    """A copy of a RepoIMU file with the glitches' reference frames written as all-zero quaternions,
    the format's "no value", for `gyrocal import` to flag invalid."""
    lines = source.read_text().splitlines(keepends=True)
    for k in np.flatnonzero(frames):
        fields = lines[k + 2].split(";")
        fields[1:5] = ["0"] * 4
        lines[k + 2] = ";".join(fields)
    out.write_text("".join(lines))


def explain(rate, quat, valid, step_s, response, bias_rad_s, latency_s, force, lag=EXPLAIN_LAG):
    """What each candidate leaves of the increment error over ``lag`` in motion (RMS per axis, arcsec),
    and per rate bin the error and the share of its variance along the rotation axis. ``force``: the
    specific force (N, 3), for a reference offset that follows it (`gravity_offset`, a mount that gives)
    and a gyro bias that does (`g_sensitivity`)."""
    corrected = corrected_rate(rate, step_s, response, bias_rad_s, latency_s)
    starts, gyro, ref = increments(rate, quat, valid, step_s, lag, corrected, 3)
    error = (gyro.inv() * ref).as_rotvec()
    speed = np.linalg.norm(rate[starts], axis=1)
    moving = speed > MOVING_RAD_S
    error, ref, speed, starts, gyro = error[moving], ref[moving], speed[moving], starts[moving], gyro[moving]
    window = np.floor(starts * step_s / EXPLAIN_WINDOW_S).astype(int)
    force_turned = np.vstack([np.zeros(3), np.cumsum(0.5 * (force[1:] + force[:-1]) * step_s, axis=0)])
    one = np.zeros(len(starts), int)
    acceleration = savgol_filter(corrected, 7, 2, deriv=1, delta=step_s, axis=0)
    products = np.stack([corrected[:, 1] * corrected[:, 2], corrected[:, 0] * corrected[:, 2],
                         corrected[:, 0] * corrected[:, 1]], axis=1)
    timing = (ref.apply(corrected[starts + lag]) - corrected[starts])[:, :, None]
    candidates = {
        "none": (np.zeros((len(starts), 3, 0)), one),
        "a timing offset per window (1 a window)": (timing, window),
        "a bias per window (3 a window)": (np.broadcast_to(np.eye(3) * lag * step_s, (len(starts), 3, 3)), window),
        "a scale factor per axis per window (3 a window)": (np.einsum("ni,ij->nij", gyro.as_rotvec(), np.eye(3)), window),
        "K x angular acceleration (9)": (_response_regressors(ref, acceleration[starts], acceleration[starts + lag]), one),
        "K x omega_i omega_j (9)": (_response_regressors(ref, products[starts], products[starts + lag]), one),
        "K x omega_i^2 (9)": (_response_regressors(ref, corrected[starts] ** 2, corrected[starts + lag] ** 2), one),
        "K x specific force (9)": (_response_regressors(ref, force[starts], force[starts + lag]), one),
        "G x specific force on the gyro (9)": (np.einsum("ni,jk->njki", force_turned[starts + lag] - force_turned[starts],
                                                        np.eye(3)).reshape(len(starts), 3, 9), one),
    }
    left = {name: _left(error, regs, groups) for name, (regs, groups) in candidates.items()}
    axis = corrected[starts] + corrected[starts + lag]
    along = np.sum(error * axis, axis=1) / np.linalg.norm(axis, axis=1)
    bins = []
    which = np.digitize(speed, RATE_BINS_RAD_S) - 1
    for b in np.unique(which):
        sel = which == b
        if sel.sum() > 20:
            total = np.mean(np.sum(error[sel] ** 2, axis=1))
            bins.append((b, float(np.sqrt(total / 3) / ARCSEC_RAD), float(np.mean(along[sel] ** 2) / total), int(sel.sum())))
    return left, bins


def fit_gyro(rate, quat, valid, step_s, lag=29):
    """One 3x3 response, bias (rad/s) and latency (s, positive: the gyro late) from the increments over
    ``lag`` samples, by least squares."""
    def residual(p):
        e, _ = lag_errors(rate, quat, valid, step_s, lag, np.eye(3) + p[:9].reshape(3, 3), p[10:13], p[9] * 1e-3, 3 * lag)
        return e.ravel()
    p = least_squares(residual, np.zeros(13), x_scale=np.r_[np.full(9, 1e-3), 1.0, np.full(3, 1e-3)]).x
    return np.eye(3) + p[:9].reshape(3, 3), p[10:13], p[9] * 1e-3


def table(rate, quat, valid, step_s, response, bias, latency_s):
    """RMS error (arcsec, per axis) and count per (lag, rate bin)."""
    rows = []
    for lag in LAGS:
        e, mean_rate = lag_errors(rate, quat, valid, step_s, lag, response, bias, latency_s)
        which = np.digitize(mean_rate, RATE_BINS_RAD_S) - 1
        for b in range(len(RATE_BINS_RAD_S) - 1):
            sel = which == b
            if sel.sum() > 5:
                rows.append((lag * step_s, b, float(np.sqrt(np.mean(e[sel] ** 2)) / ARCSEC_RAD), int(sel.sum())))
    return rows


def main():
    p = argparse.ArgumentParser()
    p.add_argument("trials", type=Path, nargs="+")
    p.add_argument("--figure", type=Path)
    p.add_argument("--explain", action="store_true", help="which candidate takes the 0.1-s error in motion")
    p.add_argument("--write-flagged", type=Path, metavar="DIR",
                   help="write each RepoIMU trial to DIR with its glitches' reference frames flagged missing")
    a = p.parse_args()
    results = {}
    for path in a.trials:
        rate, quat, valid, step = load(path)
        response, bias, latency = fit_gyro(rate, quat, valid, step)
        print(f"{path.stem}: response diagonal - 1 (ppm) {np.round((np.diag(response) - 1) * 1e6)}, "
              f"bias (deg/h) {np.round(np.degrees(bias) * 3600, 1)}, latency {latency * 1e3:.2f} ms (gyro late)")
        rows = table(rate, quat, valid, step, response, bias, latency)
        results[path.stem] = rows
        for lag_s, b, rms, n in rows:
            lo, hi = RATE_BINS_RAD_S[b], RATE_BINS_RAD_S[b + 1]
            print(f"  lag {lag_s:7.3f} s  |omega| {lo:4.2f}-{hi:5.2f} rad/s  RMS {rms:7.0f} arcsec per axis  ({n} lags)")
        if a.explain:
            left, bins = explain(rate, quat, valid, step, response, bias, latency, specific_force(path))
            print(f"  in motion (|omega| > {MOVING_RAD_S} rad/s), lag {EXPLAIN_LAG * step:.3f} s: RMS per axis left by")
            for name, rms in left.items():
                print(f"    {name:48s} {rms:6.0f} arcsec")
            corrected = corrected_rate(rate, step, response, bias, latency)
            n, moving, share, before, after = glitches(rate, quat, valid, step, corrected)
            print(f"    reference glitches (one-sample steps off the gyro's by > {GLITCH_OFF:.0%} along it): {n} of {moving} "
                  f"moving steps, {share:.0%} of the one-sample error along the axis; the {EXPLAIN_LAG * step:.3f}-s error "
                  f"{before:.0f} arcsec, {after:.0f} without the lags that end on them")
            for b, rms, share, n in bins:
                lo, hi = RATE_BINS_RAD_S[b], RATE_BINS_RAD_S[b + 1]
                print(f"    |omega| {lo:4.2f}-{hi:5.2f} rad/s: RMS {rms:5.0f} arcsec per axis, "
                      f"{share:.2f} of the variance along the rotation axis ({n} lags)")
        if a.write_flagged and path.suffix == ".csv":
            frames = glitch_frames(rate, quat, valid, step, corrected_rate(rate, step, response, bias, latency))[0]
            a.write_flagged.mkdir(parents=True, exist_ok=True)
            write_flagged(path, frames, a.write_flagged / path.name)
            print(f"  wrote {a.write_flagged / path.name}: {frames.sum()} reference frames flagged missing")
    if a.figure:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(1, len(results), figsize=(5.5 * len(results), 4.2), squeeze=False)
        for ax, (name, rows) in zip(axes[0], results.items()):
            rows = np.array(rows)
            for b in np.unique(rows[:, 1]).astype(int):
                sel = rows[:, 1] == b
                label = "rest" if b == 0 else f"|omega| {RATE_BINS_RAD_S[b]}-{RATE_BINS_RAD_S[b + 1]} rad/s"
                ax.loglog(rows[sel, 0], rows[sel, 2], "o-", label=label)
            lags = rows[:, 0]
            ref = np.sqrt(lags / lags.min()) * rows[rows[:, 1] == 3, 2][0] if (rows[:, 1] == 3).any() else None
            if ref is not None:
                ax.loglog(lags, ref, "k:", label="grows as sqrt(lag)")
            ax.set(xlabel="lag (s)", ylabel="increment error RMS per axis (arcsec)", title=name)
            ax.legend(fontsize=7)
        fig.tight_layout()
        a.figure.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(a.figure, dpi=110)
        print("figure:", a.figure)


if __name__ == "__main__":
    main()
