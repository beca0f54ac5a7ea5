"""Where a finished run's residual lives (issue 42): in the body frame, or accumulated in the inertial
frame, and what it grows with. Reads a run's folder (``results/<campaign>``), one model's point estimate
and the preprocessed maneuvers; fits nothing.

For each maneuver, on the in-loop channel set:

- the residual's RMS, body axes (arcsec);
- the inertial-frame error at the end against the start (deg), the drift rates in the first and last
  rests (deg/s), and, where ``gyro.csv`` had accelerometer columns, the inertial direction of the
  specific force (which axis is vertical: an isotropic g-sensitivity drifts along it);
- the drift a two-sample coning correction would remove, ``sum R (dtheta_(k-1) x dtheta_k) / 12`` in
  the inertial frame (deg): the integration error of the gyro's increments under coning motion;
- the error's change between two reference samples against the angle turned between them (rad): a
  random walk of the gyro grows as its square root without bound, an error bounded in size (a
  reference error, an attitude offset) stops growing;
- what is left of the body-frame residual once a constant rotation between the reference's and the
  gyros' frames is taken out (an error of the estimated mounting: ``(I - dR(t)^T) delta`` to first
  order, ``dR`` the reference's rotation since the start), and with a constant inertial offset too.

    python studies/inertial_drift.py results/<campaign> [--model baseline] [--plugins FILE ...]
"""

import argparse
import itertools
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from gyrocal.inference import errormodel
from gyrocal.model.units import rad_to_arcsec
from gyrocal.pipeline.readback import load_model_run

REST_RAD_S = 0.02
"""Below this body rate a reference sample is at rest."""

TRAVELLED_EDGES_RAD = (0.0, 0.01, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 1000.0)

MAX_PAIRED_SAMPLES = 3000
"""`travelled_table` pairs at most this many reference samples (evenly spaced): every pair of 10^4 is 1 GB."""


def rest_runs(at_rest) -> list:
    """The runs of consecutive rest samples, three or more long, as index arrays."""
    idx = np.flatnonzero(at_rest)
    runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if len(idx) else []
    return [r for r in runs if len(r) >= 3]


def rest_drift_deg_s(time, error, run) -> np.ndarray:
    """The inertial error's slope (deg/s) over one run of rest samples."""
    return np.degrees(np.polyfit(time[run] - time[run[0]], error[run], 1)[0])


def coning_deg(data) -> np.ndarray:
    """(3,) the inertial sum of the two-sample coning terms of the gyro's increments (deg), turned by
    the reference attitude at each gyro interval."""
    inc = np.asarray(data.increments, dtype=float)
    terms = np.vstack([np.zeros((1, 3)), np.cross(inc[:-1], inc[1:]) / 12.0])
    times = np.clip(data.gyro_time[1:], data.st_time[0], data.st_time[-1])
    attitude = Slerp(data.st_time, Rotation.from_quat(data.st_quat))(times)
    return np.degrees(attitude.apply(terms).sum(axis=0))


def travelled_table(data, body_error) -> list:
    """Per bin of angle turned between two reference samples: pairs, RMS of the change of the body
    error (arcsec), median time apart (s)."""
    turned = np.concatenate([[0.0], np.cumsum(np.linalg.norm(data.increments, axis=1))])
    kept = np.unique(np.linspace(0, len(data.st_time) - 1, min(len(data.st_time), MAX_PAIRED_SAMPLES)).astype(int))
    time, error = data.st_time[kept], np.asarray(body_error)[kept]
    theta = np.interp(time, data.gyro_time, turned)
    i, j = np.triu_indices(len(theta), 1)
    travelled, apart = theta[j] - theta[i], time[j] - time[i]
    change = np.sum((error[j] - error[i]) ** 2, axis=1) / 3.0
    rows = []
    for lo, hi in itertools.pairwise(TRAVELLED_EDGES_RAD):
        k = (travelled >= lo) & (travelled < hi)
        if k.any():
            rows.append((lo, hi, int(k.sum()), float(rad_to_arcsec(np.sqrt(change[k].mean()))), float(np.median(apart[k]))))
    return rows


def frame_offsets(data, body_error) -> tuple:
    """RMS (arcsec) of the body-frame residual left by a least-squares frame offset ``delta`` (deg) and by
    ``delta`` with a constant inertial offset (deg)."""
    turned = (Rotation.from_quat(data.attitude0_quat).inv() * Rotation.from_quat(data.st_quat)).as_matrix()
    back = np.swapaxes(turned, 1, 2)
    y = np.asarray(body_error, dtype=float).ravel()
    out = []
    for design in (np.eye(3)[None] - back, np.concatenate([np.eye(3)[None] - back, back], axis=2)):
        x = design.reshape(len(y), -1)
        coef = np.linalg.lstsq(x, y, rcond=None)[0]
        out += [float(rad_to_arcsec(np.sqrt(np.mean((y - x @ coef) ** 2)))), np.degrees(coef)]
    return tuple(out)


def main():
    """Print each maneuver's figures, in the campaign's order (`load_model_run`: as the fit's biases are)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="a run's results/<campaign> folder")
    parser.add_argument("--model", default="baseline")
    parser.add_argument("--plugins", nargs="*", default=[])
    args = parser.parse_args()
    maneuvers, est = load_model_run(args.run, args.model, args.plugins)
    for m, data in enumerate(maneuvers):
        lin = errormodel.linearize(data, est.spec, est.theta, est.biases[m])
        body, inertial = lin.body_error[:, 0], lin.z[:, 0]
        at_rest = np.linalg.norm(lin.st_body_rate, axis=1) < REST_RAD_S
        print(f"{data.id}: model {args.model}, {len(data.st_time)} reference samples over "
              f"{data.st_time[-1] - data.st_time[0]:.1f} s, {100 * at_rest.mean():.0f} % at rest")
        print("  residual RMS, body x y z (arcsec):", np.round(rad_to_arcsec(np.sqrt(np.mean(body**2, axis=0))), 1))
        print("  inertial error, end - start (deg):", np.round(np.degrees(inertial[-1] - inertial[0]), 3))
        runs = rest_runs(at_rest)
        for name, run in (("first", runs[0]), ("last", runs[-1])) if len(runs) > 1 else (("only", r) for r in runs):
            drift = rest_drift_deg_s(data.st_time, inertial, run)
            print(f"  drift in the {name} rest, {len(run)} samples (deg/s):", np.round(drift, 4))
        if not runs:
            print("  no rest of three reference samples")
        if {"acc_x", "acc_y", "acc_z"} <= set(data.extras):
            force = np.column_stack([data.extras[f"acc_{a}"] for a in "xyz"])[data.st_interval()[0]]
            up = Rotation.from_quat(data.st_quat).apply(force).mean(axis=0)
            print("  specific force, inertial (unit):  ", np.round(up / np.linalg.norm(up), 3))
        print("  coning terms summed, inertial (deg):", np.round(coning_deg(data), 4))
        left, delta, both, coef = frame_offsets(data, body)
        print(f"  left by a frame offset: {left:.1f} arcsec RMS (offset {np.round(delta, 3)} deg); with an inertial "
              f"offset too: {both:.1f} (inertial {np.round(coef[3:], 3)} deg)")
        print("  change of the body error against the angle turned between two samples:")
        for lo, hi, pairs, rms, apart in travelled_table(data, body):
            print(f"    {lo:7.2f} to {hi:7.2f} rad: {pairs:8d} pairs, RMS {rms:8.1f} arcsec, median {apart:6.1f} s apart")


if __name__ == "__main__":
    main()
