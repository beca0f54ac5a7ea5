"""The classic method against the truth on simulated MOM-like campaigns: the paper's (trusted bias,
one solve) and ``classic.csv``'s (bias from the holds, solved again about its estimate), each with
its delta-method sd, at the default scenario's truth and residual bias, at a bias 30 times
larger, at truths drawn as the validation study draws them, and under a bias drift (the limit).

    python studies/classic_accuracy.py [--campaigns 20] [--out studies/data/classic_accuracy.csv]

Prints one row per condition, estimator and parameter kind: RMSE and largest error against the
truth, the mean sd, the z-scores' sd and the share within 2 sd (ppm for scale factors, arcsec for
misalignments)."""

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

CONDITIONS = {"bias 0.01 deg/h (default)": (0.01, 0.0, False), "bias 0.3 deg/h": (0.3, 0.0, False),
              "truths 5000 ppm, 1000 arcsec": (0.01, 0.0, True),
              "drift 0.2 deg/h/h": (0.01, 0.2, False), "drift 2 deg/h/h": (0.01, 2.0, False)}
"""name -> (residual bias sd in deg/h, bias drift in deg/h/h, truths drawn from the default prior
(sd 5000 ppm and 1000 arcsec) instead of the paper's tables)."""


def errors(seed: int, bias_sd: float, drift: float, drawn: bool) -> pd.DataFrame:
    from gyrocal.inference.fit import classic
    from gyrocal.maneuvers import preprocess
    from gyrocal.model import spec
    from gyrocal.simulation import simulate

    scenario = simulate.load_scenario(Path(__file__).parents[1] / "config/scenarios/mom.yaml")
    scenario["seed"] = seed
    scenario["gyro"]["bias_sd_deg_h"] = bias_sd
    scenario["effects"]["bias_drift_deg_h_per_h"] = drift
    if drawn:
        simulate.scatter_truth(scenario, np.random.default_rng(seed), 5000.0, 1000.0)
    sim, truth = simulate.simulate(scenario)
    maneuvers = [preprocess.slice_maneuver(sim, m.id) for m in sim.maneuvers]
    stated = {**scenario["star_tracker"], "arw_deg_sqrt_h": scenario["gyro"]["arw_deg_sqrt_h"]}
    parts = []
    for bias, iterations in (("trusted", 1), ("holds", classic.PIPELINE_ITERATIONS)):
        table = classic.classic_table(maneuvers, spec.baseline(maneuvers[0].channels), bias, stated, iterations)
        table["error"] = table["value"] - [truth["parameters"][r.channel][r.parameter] for r in table.itertuples()]
        parts.append(table.assign(estimator=f"classic_{bias}", seed=seed))
    return pd.concat(parts, ignore_index=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--campaigns", type=int, default=20)
    parser.add_argument("--out", default=str(Path(__file__).parent / "data" / "classic_accuracy.csv"))
    args = parser.parse_args()
    rows = []
    for name, (bias_sd, drift, drawn) in CONDITIONS.items():
        for seed in range(args.campaigns):
            rows.append(errors(seed, bias_sd, drift, drawn).assign(condition=name))
    frame = pd.concat(rows, ignore_index=True)
    frame["z"] = frame["error"] / frame["sd"]
    table = (frame.groupby(["condition", "estimator", "unit"], sort=False)
             .agg(rmse=("error", lambda e: np.sqrt(np.mean(e**2))), max_abs=("error", lambda e: e.abs().max()),
                  mean_sd=("sd", "mean"), z_sd=("z", "std"), within_2sd=("z", lambda z: np.mean(np.abs(z) < 2)),
                  n=("z", "size"))
             .reset_index())
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.out, index=False, float_format="%.4g")
    print(table.to_markdown(index=False, floatfmt=".3g"))


if __name__ == "__main__":
    main()
