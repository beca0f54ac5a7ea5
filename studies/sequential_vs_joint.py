"""Two campaigns of one unit combined two ways: sequentially (the second campaign's posterior with
the first one's ``calibration.csv`` as its prior, ``prior_from``) and jointly (`gyrocal joint`).

Each pair is the scenario's truth at two seeds. Campaign A runs through its posterior and
``calibration.csv``; campaign B runs its posterior with ``prior_from`` = A's calibration; the joint
fit reads both point estimates. Printed: for the first pair, each parameter's mean and sd both
ways and their differences in the joint sd; over all pairs, the spread of those differences and
each method's error against the truth in its own sd.

    PYTHONPATH=src python studies/sequential_vs_joint.py --pairs 3 --out /tmp/sequential
"""

import argparse
import copy
import json
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

ROOT = Path(__file__).resolve().parents[1]


def run_pair(i: int, scenario_path: str, out: Path, cfg: dict) -> pd.DataFrame:
    """One pair: A's and B's (sequential) calibration.csv, and the joint one, per parameter."""
    from gyrocal.pipeline.paths import CampaignPaths
    from gyrocal.pipeline.run import calibrate_campaign
    from gyrocal.pipeline.settings import PosteriorSettings
    from gyrocal.pipeline.steps import calibrate, posterior
    from gyrocal.pipeline.steps.joint import run as joint
    from gyrocal.simulation.simulate import run as simulate

    runs = {}
    for tag, seed in (("a", 20_000 + 2 * i), ("b", 20_001 + 2 * i)):
        paths = CampaignPaths.under(out / f"{i:02d}_{tag}" / "run")
        if not Path(paths.model("baseline").point_estimate).is_file():  # a finished step is not run again
            simulate(scenario_path, out / f"{i:02d}_{tag}", seed)
            calibrate_campaign(out / f"{i:02d}_{tag}" / "campaign", paths, cfg, ["baseline"], figures=False,
                               through="point_estimate")
        runs[tag] = (paths, json.loads(Path(paths.input_json).read_text())["maneuvers"])
    truth = json.loads((out / f"{i:02d}_a" / "truth.json").read_text())["parameters"]
    (pa, ids_a), (pb, ids_b) = runs["a"], runs["b"]
    sequential = copy.deepcopy(cfg)
    sequential["prior_from"] = pa.model("baseline").calibration
    for paths, ids, settings in ((pa, ids_a, cfg), (pb, ids_b, sequential)):
        if not Path(paths.model("baseline").calibration).is_file():
            posterior.run(paths.maneuvers(ids), paths.model("baseline").point_estimate,
                    paths.model("baseline"), PosteriorSettings.of(settings))
            calibrate.run(paths.maneuvers(ids), *(getattr(paths.model("baseline"), f)
                                                  for f in ("point_estimate", "summary", "calibration", "correction")))
    joint([pa.root, pb.root], out / f"{i:02d}_joint", "baseline", cfg["priors"])
    keys = ["channel", "parameter"]
    seq = pd.read_csv(pb.model("baseline").calibration)[keys + ["unit", "mean", "sd"]]
    jnt = pd.read_csv(out / f"{i:02d}_joint" / "calibration.csv")[keys + ["mean", "sd"]]
    table = seq.merge(jnt, on=keys, suffixes=("_sequential", "_joint"))
    table.insert(0, "pair", i)
    table["truth"] = [truth[c][p] for c, p in zip(table["channel"], table["parameter"])]
    table["difference_in_joint_sd"] = (table["mean_sequential"] - table["mean_joint"]) / table["sd_joint"]
    table["sd_ratio"] = table["sd_sequential"] / table["sd_joint"]
    for how in ("sequential", "joint"):
        table[f"error_in_sd_{how}"] = (table[f"mean_{how}"] - table["truth"]) / table[f"sd_{how}"]
    return table


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=3)
    parser.add_argument("--scenario", default=str(ROOT / "tests" / "data" / "tiny.yaml"))
    parser.add_argument("--out", default="/tmp/sequential")
    args = parser.parse_args()
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table = pd.concat([run_pair(i, args.scenario, out, cfg) for i in range(args.pairs)])
    table.to_csv(out / "sequential_vs_joint.csv", index=False)
    first = table[table["pair"] == 0]
    print(first[["channel", "parameter", "unit", "truth", "mean_sequential", "sd_sequential", "mean_joint", "sd_joint",
                 "difference_in_joint_sd", "sd_ratio"]].to_markdown(index=False, floatfmt=".2f"))
    print(f"\nover {args.pairs} pairs, {len(table)} parameters: (sequential - joint) / joint sd: mean "
          f"{table['difference_in_joint_sd'].mean():+.3f}, sd {table['difference_in_joint_sd'].std():.3f}, "
          f"max |.| {table['difference_in_joint_sd'].abs().max():.3f}; sequential sd / joint sd: median "
          f"{table['sd_ratio'].median():.3f}, range {table['sd_ratio'].min():.3f}-{table['sd_ratio'].max():.3f}")
    for how in ("sequential", "joint"):
        z = table[f"error_in_sd_{how}"]
        print(f"{how}: error against the truth in its own sd: rms {np.sqrt(np.mean(z**2)):.3f}, share within "
              f"1.96 sd {np.mean(np.abs(z) < 1.96):.3f}")


if __name__ == "__main__":
    main()
