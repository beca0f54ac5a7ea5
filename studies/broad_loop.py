"""The criticism loop on one BROAD trial (issues 41/42): why a single 200-s free maneuver is refused and
what its residual is made of. For each window length (the trial's motion cut into windows, each its own
maneuver: its own anchor and bias) and each model (baseline, + st_latency, + g_sensitivity, ...): the
REML noise scales, the residual RMS per axis, the whiteness and the ranking's first entries.

    python studies/broad_loop.py CAMPAIGN [--windows 0 40 20 10] [--effects st_latency ...]
"""

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np
import yaml

from gyrocal import checks
from gyrocal.criticism import diagnostics
from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import linearize_all, point_estimate
from gyrocal.inference.noise.covariance import noise_knowledge
from gyrocal.maneuvers import preprocess
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import ARCSEC_RAD

NOISE = yaml.safe_load((Path(__file__).parents[1] / "config" / "config.yaml").read_text())["noise"]
"""The default run's noise knowledge where campaign.yaml is silent."""


def windowed(campaign, window_s: float):
    """The campaign with each maneuver cut into windows of about ``window_s`` (0: as it is)."""
    if not window_s:
        return campaign
    out = []
    for m in campaign.maneuvers:
        n = max(1, round((m.t_end - m.t_start) / window_s))
        edges = np.linspace(m.t_start, m.t_end, n + 1)
        step = float(np.median(np.diff(campaign.gyro_time)))
        for i in range(n):
            out.append(dataclasses.replace(m, id=f"{m.id}_w{i + 1}", t_start=float(edges[i]) + (step if i else 0.0),
                                           t_end=float(edges[i + 1])))
    return dataclasses.replace(campaign, maneuvers=tuple(out))


def fit(campaign, names):
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, NOISE)
    spec = ModelSpec.build("+".join(names), effects.resolve("m", names, {}), maneuvers[0].channels)
    est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    lins, noises = linearize_all(maneuvers, est)
    res = np.concatenate([lin.z[:, 0, :] - est.chi0[m] for m, lin in enumerate(lins)])
    white = diagnostics.whiteness(maneuvers, zip(lins, noises), est)
    ranking, _ = diagnostics.rank(maneuvers, est, list(maneuvers[0].extras), (), white)
    return maneuvers, est, res, white, ranking


def main():
    p = argparse.ArgumentParser()
    p.add_argument("campaign", type=Path)
    p.add_argument("--windows", type=float, nargs="+", default=[0.0])
    p.add_argument("--effects", nargs="*", default=[])
    a = p.parse_args()
    campaign, _ = checks.read_checked(a.campaign)
    for w in a.windows:
        for extra in [[]] + [[e] for e in a.effects]:
            names = list(effects.BASELINE) + extra
            t0 = time.perf_counter()
            maneuvers, est, res, white, ranking = fit(windowed(campaign, w), names)
            s = np.exp(est.log_sigma)
            rms = np.sqrt(np.mean(res ** 2, axis=0)) / ARCSEC_RAD
            print(f"window {w:5.0f} s ({len(maneuvers)} maneuvers) {'+'.join(extra) or 'baseline':14s} "
                  f"REML cross/about {s[0] / ARCSEC_RAD:.3g}/{s[1] / ARCSEC_RAD:.3g} arcsec ARW "
                  f"{s[2] / (np.pi / 180 / 60):.3g} deg/sqrt(h); residual RMS {np.round(rms).astype(int)} arcsec; "
                  f"{time.perf_counter() - t0:.0f} s")
            print("    white:", white if not hasattr(white, "summary") else white.summary())
            for r in ranking[:4]:
                print("    rank:", r)


if __name__ == "__main__":
    main()
