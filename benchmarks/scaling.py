"""Cost against telemetry length: prints figures, asserts nothing.

    python benchmarks/scaling.py [--factors 1 2 4 8] [--longer] [--repeats 1] [--csv OUT.csv]

The default MOM-like scenario is flown k times over (its six maneuvers repeated, each copy
its own maneuver), so the campaign holds k times the samples at the same rates; with
``--longer``, each of its six maneuvers holds k times as long instead (a cost that grows with
one maneuver's length shows there, not in the number of maneuvers). Each stage of the
pipeline runs through the library in this one process, and its wall time (the least of
``--repeats`` runs, which a busy machine inflates least) is printed per k with its ratio to
k = 1 and the log-log slope against the number of star-tracker samples between the smallest
and largest k (1 is linear). The sampler runs a fixed number of steps, so its figure is the
cost per step; the leave-one-block-out log-likelihood (PSIS-LOO's pointwise terms) is timed
on its own (with the fit table and predictive draws), since its cost grew with the square of
the length before `selectedinverse`.
"""

import argparse
import copy
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]


def repeated(scenario: dict, k: int) -> dict:
    """The scenario's maneuvers flown ``k`` times, in order, each copy with its own id."""
    out = copy.deepcopy(scenario)
    out["maneuvers"] = [{**m, "id": f"{m['id']}_{i}"} for i in range(k) for m in scenario["maneuvers"]]
    return out


def longer(scenario: dict, k: int) -> dict:
    """The scenario with each maneuver's holds ``k`` times as long (same maneuvers, same rates)."""
    out = copy.deepcopy(scenario)
    out["maneuver_defaults"]["hold_s"] = k * scenario["maneuver_defaults"]["hold_s"]
    return out


def stage_times(scenario: dict, cfg: dict) -> dict:
    from gyrocal import checks
    from gyrocal.inference.fit import classic
    from gyrocal.inference.fit.estimate import point_estimate
    from gyrocal.inference.noise.covariance import noise_knowledge
    from gyrocal.inference.sampling import inferencedata, posterior
    from gyrocal.inference.sampling.priors import model_priors
    from gyrocal.maneuvers import preprocess
    from gyrocal.model.spec import baseline
    from gyrocal.simulation import simulate

    times = {}

    def timed(name, call):
        start = time.perf_counter()
        out = call()
        times[name] = time.perf_counter() - start
        return out

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scenario.yaml"
        path.write_text(yaml.safe_dump(scenario))
        timed("simulate (and write)", lambda: simulate.run(path, tmp))
        campaign, _ = timed("validate (read and check)", lambda: checks.read_checked(Path(tmp) / "campaign"))
    maneuvers = timed("preprocess", lambda: [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers])
    spec = baseline(campaign.channels)
    stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    theta0 = timed("classic", lambda: classic.classic_start(maneuvers, spec))
    est = timed("point estimate (REML + WLS)", lambda: point_estimate(maneuvers, spec, stated, theta0))
    priors = model_priors(est, cfg["priors"])
    sampler_cfg = {**cfg["sampler"], "initial_steps": 100, "min_tau_multiple": 0, "max_steps": 100}
    post = timed(f"posterior: grid + {cfg['sampler']['burn_steps']} burn-in + 100 steps", lambda: posterior.run(
        posterior.prepare(maneuvers, est, priors, cfg["grid"]), sampler_cfg, cfg["seed"]))
    draws = post.ensemble_draws()[:, :: max(1, post.ensemble_draws().shape[1] // 250)]
    timed("posterior: LOO terms, fit, predictive (1000 draws)", lambda: inferencedata._fit_and_predictive(
        post, maneuvers, draws, cfg["sampler"], cfg["seed"]))
    return times, sum(len(d.st_time) for d in maneuvers)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--factors", type=int, nargs="+", default=[1, 2, 4, 8])
    parser.add_argument("--longer", action="store_true", help="k times longer holds, not k times the maneuvers")
    parser.add_argument("--repeats", type=int, default=1, help="runs per factor; each stage's least time is kept")
    parser.add_argument("--csv", help="also write the times here, a row per factor and stage (what docs/images/scaling.py draws)")
    args = parser.parse_args()
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    from gyrocal.simulation.simulate import load_scenario
    scenario = load_scenario(ROOT / "config/scenarios/mom.yaml")
    rows = {}
    for k in args.factors:
        runs = [stage_times((longer if args.longer else repeated)(scenario, k), cfg) for _ in range(args.repeats)]
        rows[k] = ({stage: min(times[stage] for times, _ in runs) for stage in runs[0][0]}, runs[0][1])
        print(f"k={k}: {rows[k][1]} star-tracker samples, {sum(rows[k][0].values()):.1f} s in all", flush=True)
    first, last = args.factors[0], args.factors[-1]
    print(f"\n{'stage':45s}" + "".join(f"{f'{k}x (s)':>10s}" for k in args.factors) + f"{'ratio':>8s}{'slope':>7s}")
    for stage in rows[first][0]:
        t = [rows[k][0][stage] for k in args.factors]
        slope = np.log(t[-1] / t[0]) / np.log(rows[last][1] / rows[first][1])
        print(f"{stage:45s}" + "".join(f"{v:10.2f}" for v in t) + f"{t[-1] / t[0]:8.1f}{slope:7.2f}")
    if args.csv:
        import pandas as pd

        pd.DataFrame([{"factor": k, "st_samples": n, "stage": stage, "seconds": round(t, 3)}
                      for k, (times, n) in rows.items() for stage, t in times.items()]).to_csv(args.csv, index=False)
    print(f"\nratio: time at {last}x over time at {first}x; slope: log-log against the star-tracker samples, "
          "1 = linear in the telemetry length")


if __name__ == "__main__":
    main()
