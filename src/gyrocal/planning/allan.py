"""Gyro noise from a static recording: the Allan deviation (IEEE Std 952-1997, annex C), through
`allantools`, and the angle random walk it gives, the noise knowledge a campaign states."""

import allantools
import numpy as np
import pandas as pd

from gyrocal.model.units import DEG_H_RAD_S

__all__ = ["ARW_TAU_S", "allan_table", "angle_random_walk", "cluster_times", "static_report"]

ARW_TAU_S = 1.0
"""The angle random walk is read off at this cluster time, where a rate gyro's white noise still
dominates its bias instability: ``ARW = sigma(tau) sqrt(tau)`` on the slope -1/2 of the curve."""


def cluster_times(n: int, dt_s: float, per_decade: int = 4) -> np.ndarray:
    """Cluster times from one sample to a tenth of the record, log-spaced, with ``ARW_TAU_S``
    among them (beyond a tenth, too few independent clusters are left)."""
    top = np.log10(max(n * dt_s / 10.0, 2 * dt_s))
    taus = 10.0 ** np.arange(np.log10(dt_s), top, 1.0 / per_decade)
    clusters = np.unique(np.round(np.append(taus, ARW_TAU_S) / dt_s))
    return clusters[clusters >= 1] * dt_s


def allan_table(increments_rad: np.ndarray, dt_s: float, names) -> pd.DataFrame:
    """Overlapping Allan deviation of each channel's rate (deg/h), and ``sigma(tau) sqrt(tau)``
    (deg/sqrt(h)), flat where angle random walk dominates. ``increments_rad`` (K, n) over equal
    intervals ``dt_s``, the gyro at rest."""
    angle = np.vstack([np.zeros(increments_rad.shape[1]), np.cumsum(increments_rad, axis=0)])
    taus = cluster_times(len(increments_rad), dt_s)
    rows = {}
    for i, name in enumerate(names):
        tau, adev, _, _ = allantools.oadev(angle[:, i], rate=1.0 / dt_s, data_type="phase", taus=taus)
        rows[f"{name} adev_deg_h"] = adev / DEG_H_RAD_S
        rows[f"{name} arw_deg_sqrt_h"] = adev * np.sqrt(tau) / DEG_H_RAD_S / 60.0
    return pd.DataFrame(rows, index=pd.Index(tau, name="tau_s"))


def angle_random_walk(table: pd.DataFrame) -> pd.Series:
    """Each channel's angle random walk (deg/sqrt(h)) at the cluster time nearest `ARW_TAU_S`
    (the series' name)."""
    arw = table.filter(like="arw_deg_sqrt_h")
    row = arw.iloc[int(np.argmin(np.abs(arw.index.to_numpy() - ARW_TAU_S)))]
    return row.rename(lambda c: c.removesuffix(" arw_deg_sqrt_h"))


def static_report(imported, names, path) -> str:
    """What ``gyrocal allan`` prints for one static recording read through a mapping (``names``:
    its gyro channels, in the mapping's order)."""
    from gyrocal.io.telemetry import TelemetryError
    steps = np.diff(imported.time)
    dt_s = float(np.median(steps))
    uneven = np.flatnonzero(np.abs(steps - dt_s) > 0.01 * dt_s)
    if uneven.size:
        raise TelemetryError(f"{path}: row {int(uneven[0]) + 2} of the data: the gyro interval is "
                             f"{steps[uneven[0]]:.6g} s where the file's is {dt_s:.6g} s; the Allan deviation "
                             "needs equal intervals")
    # A sampled rate holds over its interval (Allan's rectangular cluster); its trapezoid increments
    # would read the ARW low by sqrt(1 - 0.75/m) at a cluster of m samples: half at one sample.
    increments = imported.increments[1:] if imported.rate is None else imported.rate * dt_s
    table = allan_table(increments, dt_s, names)
    arw = angle_random_walk(table)
    mean = np.rad2deg(increments.sum(axis=0) / (len(increments) * dt_s))
    lines = [f"{path}: {len(increments)} intervals of {dt_s:g} s at rest ({len(increments) * dt_s:.0f} s)",
             "", table.round(3).to_string(), "",
             "mean rate (turn-on bias, with the Earth's rate), deg/s: "
             + ", ".join(f"{n} {m:+.4f}" for n, m in zip(names, mean)),
             f"angle random walk at tau = {arw.name:g} s, deg/sqrt(h): "
             + ", ".join(f"{n} {v:.3f}" for n, v in arw.items()),
             f"state it as  arw_deg_sqrt_h: {float(np.sqrt(np.mean(arw**2))):.2f}   (the channels' RMS; in "
             "campaign.yaml under gyro:, or in the config under noise:)"]
    return "\n".join(lines)
