"""Cost against telemetry length of the white and the correlated noise model, step by step: prints figures, asserts nothing.

    python benchmarks/correlated_cost.py [--factors 1 10 100] [--whole 1 10] [--models baseline st_correlated_noise]

The default MOM-like campaign is simulated once and its six maneuvers are flown k times over in
memory (each copy its own maneuver, with the same data): k times the telemetry at the same rates,
and, since the data repeat, the same number of optimiser steps at every k, so the figures are the
cost of the same work on k times the samples. Each factor runs in its own process (one BLAS thread,
as Snakemake gives a job). Per step, its wall time and the peak of its numpy and Python
allocations (tracemalloc, reset before each step; it slows Python-heavy steps a little, the same
at every k), and the process's peak RSS at the end:

- the point estimate as a whole, REML then WLS (at the factors of ``--whole`` only: at 100x the
  correlated REML's simplex, 100-150 profile evaluations of 600 maneuvers, does not fit the time
  this machine gives);
- the linearisation of every maneuver about the estimate (what every step starts from; up to
  ``--diagnostics-max``: beyond, the 1x maneuvers' linearisations are shared by their copies,
  which the same data allow, and their memory, 41 MB per 1x, is not in the figures);
- one evaluation of the REML profile: the correlated model's builds each maneuver's noise
  structure (its filter at tau), sums its statistics and drops it; the white model's sums the
  statistics of noise structures built once (timed as their own step, which the correlated
  model's grid repeats at each of its 7 taus);
- one node of the posterior's grid (the statistics at one noise shape; the white model's grid has
  7^2 = 49 nodes on fixed noise structures, the correlated model's 7^4 = 2,401 with the filter
  rebuilt at each of the 7 taus);
- the diagnostics' whiteness test and ranking of the candidate effects (one maneuver at a time;
  up to ``--diagnostics-max``).

Slopes are log-log against the number of star-tracker samples between the smallest and largest
factor (1 = linear).
"""

import argparse
import dataclasses
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
MODELS = {"baseline": ["scale_factor", "misalignment", "bias"],
          "st_correlated_noise": ["scale_factor", "misalignment", "bias", "st_correlated_noise"]}


def steps(k: int, model: str, whole: bool, diagnostics_max: int, linearise_max: int = 10) -> dict:
    """Time (s) and allocation peak (MB) of each step on the default campaign flown ``k`` times over."""
    from gyrocal import checks
    from gyrocal.criticism import diagnostics
    from gyrocal.inference.fit import classic
    from gyrocal.inference.fit.estimate import point_estimate
    from gyrocal.inference.fit.likelihood import campaign_stats
    from gyrocal.inference.fit.noisefit import profile_reml
    from gyrocal.inference.noise import covariance, segments
    from gyrocal.inference.sampling.noisegrid import NoiseShapes
    from gyrocal.maneuvers import preprocess
    from gyrocal.model import effects
    from gyrocal.model.spec import ModelSpec
    from gyrocal.simulation import simulate

    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    with tempfile.TemporaryDirectory() as tmp:
        simulate.run(ROOT / "config/scenarios/mom.yaml", tmp)
        campaign, _ = checks.read_checked(Path(tmp) / "campaign")
    one = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    spec = ModelSpec.build(model, effects.resolve(model, MODELS[model], {}), one[0].channels)
    stated = covariance.noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    reference = Path(tempfile.gettempdir()) / f"gyrocal-cost-{model}.npz"
    if not reference.exists():  # the 1x estimate: where every factor's steps are taken
        est1 = point_estimate(one, spec, stated, classic.classic_start(one, spec))
        tmp_ref = reference.with_suffix(".tmp.npz")
        est1.save(tmp_ref)
        tmp_ref.replace(reference)
    from gyrocal.inference.fit.estimate import PointEstimate

    est1 = PointEstimate.load(reference, effects.known([]), linearizations=False)
    span = max(m.st_time[-1] for m in one) - min(m.gyro_time[0] for m in one) + 60.0
    maneuvers = [dataclasses.replace(m, id=f"{m.id}_{i}", gyro_time=m.gyro_time + i * span,
                                     st_time=m.st_time + i * span) for i in range(k) for m in one]  # flown k times
    est = dataclasses.replace(est1, biases=np.tile(est1.biases, (k, 1)))
    tau = est.correlation_time_s
    out = {"samples": sum(len(m.st_time) for m in maneuvers), "tau_s": tau}
    tracemalloc.start()

    def timed(name, call):
        tracemalloc.reset_peak()
        start = time.perf_counter()
        result = call()
        out[name] = (time.perf_counter() - start, tracemalloc.get_traced_memory()[1] / 1e6)
        return result

    if whole:
        timed("point estimate (REML + WLS)",
              lambda: point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec)).nfev)
    if k <= linearise_max:
        lins = timed("linearise every maneuver", lambda: [est.linearize(maneuvers, m) for m in range(len(maneuvers))])
    else:  # the same data: the 1x linearisations, shared (their memory is not in the figures)
        lins = [est.linearize(one, m) for m in range(len(one))] * k
    ratios = covariance.ratios_of(est.log_sigma)

    if tau > 0:  # as the correlated REML evaluates it: each chain of maneuvers built, summed and dropped
        chained = segments.Chains.of(maneuvers)
        timed("REML profile, one evaluation",
              lambda: NoiseShapes(None, lins, est.boresight, chained=chained).profile(ratios))
    noises = timed("noise structures (the white REML's, or the grid's at one tau: the chains')",
                   lambda: [covariance.build(lin, est.boresight, tau) for lin in lins] if tau == 0
                   else list(chained.noises(lins, est.boresight, tau)))
    if tau == 0:
        timed("REML profile, one evaluation", lambda nz=noises: profile_reml(nz, ratios)[0])
    timed("posterior grid, one node", lambda nz=noises: campaign_stats(nz, covariance.unit_variances(ratios)))
    del noises

    def diagnose():
        white = diagnostics.whiteness(maneuvers, diagnostics.linearized(maneuvers, est), est)
        return diagnostics.rank(maneuvers, est, list(maneuvers[0].extras), (), white)

    if k <= diagnostics_max:
        timed("diagnostics: whiteness and ranking", diagnose)
    out["process peak RSS (MB)"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--factors", type=int, nargs="+", default=[1, 10, 100])
    parser.add_argument("--whole", type=int, nargs="*", default=[1, 10], help="factors with the whole point estimate")
    parser.add_argument("--models", nargs="+", default=list(MODELS))
    parser.add_argument("--diagnostics-max", type=int, default=10, help="the largest factor with the diagnostics")
    parser.add_argument("--one", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        model, k, whole, diagnostics_max = args.one
        print(json.dumps(steps(int(k), model, whole == "1", int(diagnostics_max), int(diagnostics_max))))
        return
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    for model in args.models:
        rows = {}
        for k in args.factors:
            proc = subprocess.run([sys.executable, __file__, "--one", model, str(k), str(int(k in args.whole)),
                               str(args.diagnostics_max)],
                                  env=env, capture_output=True, text=True)
            if proc.returncode:
                print(proc.stderr[-3000:], file=sys.stderr)
                raise SystemExit(f"{model} at {k}x failed")
            rows[k] = json.loads(proc.stdout.strip().splitlines()[-1])
            print(f"{model} {k}x: {rows[k]['samples']} star-tracker samples, {rows[k]}", flush=True)
        table(model, rows, args.factors)


def table(model, rows, factors):
    first, last = factors[0], factors[-1]
    print(f"\n{model} (tau {rows[first]['tau_s']:.1f} s where correlated): wall s / allocation peak MB")
    print("| step | " + " | ".join(f"{k}x" for k in factors) + " | slope time | slope memory |")
    print("|---" * (len(factors) + 3) + "|")
    names = [n for n in rows[first] if isinstance(rows[first][n], list)]
    for name in names:
        have = [k for k in factors if name in rows[k]]
        cells = [f"{rows[k][name][0]:.2f} s / {rows[k][name][1]:.0f} MB" if name in rows[k] else "-" for k in factors]
        slope = ["-", "-"]
        if len(have) > 1:
            n0, n1 = rows[have[0]]["samples"], rows[have[-1]]["samples"]
            slope = [f"{np.log(rows[have[-1]][name][i] / rows[have[0]][name][i]) / np.log(n1 / n0):.2f}" for i in (0, 1)]
        print(f"| {name} | " + " | ".join(cells) + f" | {slope[0]} | {slope[1]} |")
    rss = [rows[k]["process peak RSS (MB)"] for k in factors]
    print("| process peak RSS | " + " | ".join(f"{v:.0f} MB" for v in rss) + " | | "
          + f"{np.log(rss[-1] / rss[0]) / np.log(rows[last]['samples'] / rows[first]['samples']):.2f} |")
    print("samples: " + ", ".join(f"{k}x {rows[k]['samples']}" for k in factors))


if __name__ == "__main__":
    main()
