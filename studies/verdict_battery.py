"""The verdict's error rates both ways (docs/validation.md, "The verdict's error rates"): a battery of
simulated campaigns mixing right and wrong models, each through every step of a run with the
default config, its verdict set against whether the reviewed model's intervals hold the truth.

    python studies/verdict_battery.py run --n 200 --processes 2 --out OUT      # records, one JSON a campaign
    python studies/verdict_battery.py summary OUT                             # the tables

Each campaign flies the tiny test scenario (six DTG channels, five minutes a maneuver pair) with a
truth drawn afresh, and one of the kinds below: clean, large misalignments, Gauss-Markov reference
noise (3 s or 30 s), a bias ramp, a scale-factor nonlinearity or a timing offset the default models
lack. Whether a model is right is not assumed from the kind: a campaign counts as "covered" when every
channel term of the reviewed model's ``calibration.csv`` holds its truth in its 95 % interval, else
as "missed". Prints P(GO | missed) and P(NO-GO | covered) with Clopper-Pearson intervals, and the
checks behind each NO-GO on a covered campaign. Asserts nothing.
"""

import argparse
import copy
import json
import sys
import tempfile
from collections import Counter
from multiprocessing import Pool
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from snakemake.utils import validate

from gyrocal.errors import InputError
from gyrocal.pipeline import run
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.simulation import simulate
from gyrocal.study.tables import binomial_interval

ROOT = Path(__file__).resolve().parents[1]
BASE_SCENARIO = ROOT / "tests" / "data" / "tiny.yaml"
SEED = 20261129

KINDS = {
    # name: (what the scenario's sections get, the misalignments' truth: sd, or a magnitude range, arcsec)
    "clean": ({}, 100.0),
    "large_misalignment": ({}, (2000.0, 2800.0)),
    "gauss_markov_3s": ({"star_tracker": {"gm_sigma_cross_arcsec": 5.0, "gm_sigma_about_arcsec": 20.0,
                                          "gm_tau_s": 3.0}}, 100.0),
    "gauss_markov_30s": ({"star_tracker": {"gm_sigma_cross_arcsec": 5.0, "gm_sigma_about_arcsec": 20.0,
                                           "gm_tau_s": 30.0}}, 100.0),
    "bias_ramp": ({"effects": {"bias_drift_deg_h_per_h": 0.5}}, 100.0),
    "sf_nonlinearity": ({"effects": {"sf_nonlinearity_ppm_per_deg2_s2": 20000.0}}, 100.0),
    "st_latency": ({"effects": {"st_latency_s": 0.05}}, 100.0),
}
"""The battery's kinds of campaign, flown in turn: campaign i is kind ``i mod 7``."""

SF_SD_PPM = 1000.0
"""Scale factors drawn N(0, 1000 ppm), as a DTG's residual after ground calibration."""


def scenario_of(index: int) -> tuple:
    """Campaign ``index``'s scenario (the tiny one with a fresh truth and seed, and its kind's
    changes) and its kind."""
    kind = sorted(KINDS)[index % len(KINDS)]
    changes, mis_arcsec = KINDS[kind]
    scenario = yaml.safe_load(BASE_SCENARIO.read_text())
    rng = np.random.default_rng([SEED, index])
    scenario["name"], scenario["seed"] = f"battery_{index:04d}", int(rng.integers(2**31))
    for values in scenario["truth"].values():
        for key in values:
            if key.startswith("sf_"):
                values[key] = float(rng.normal(0.0, SF_SD_PPM))
            elif isinstance(mis_arcsec, tuple):  # large, of either sign, as a triad far from its nominal axes
                values[key] = float(rng.choice([-1.0, 1.0]) * rng.uniform(*mis_arcsec))
            else:
                values[key] = float(rng.normal(0.0, mis_arcsec))
    for section, values in changes.items():
        scenario.setdefault(section, {}).update(values)
    return scenario, kind


def coverage_of(calibration: pd.DataFrame, truth: dict) -> tuple:
    """How many of the channel terms with a truth lie inside their 95 % interval, and of how many."""
    rows = [(r, truth[r.channel][r.parameter]) for r in calibration.itertuples()
            if r.parameter in truth.get(r.channel, {})]
    held = sum(r.ci95_low <= value <= r.ci95_high for r, value in rows)
    return held, len(rows)


def one(args) -> dict:
    """Simulate and run campaign ``index`` with ``cfg``; its record."""
    index, cfg, out = args
    scenario, kind = scenario_of(index)
    record = {"index": index, "kind": kind}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "scenario.yaml").write_text(yaml.safe_dump(scenario))
        simulate.run(tmp / "scenario.yaml", tmp / "sim")
        truth = json.loads((tmp / "sim" / "truth.json").read_text())["parameters"]
        paths = CampaignPaths.under(tmp / "run")
        try:
            run.run_campaign(tmp / "sim" / "campaign", paths, copy.deepcopy(cfg))
        except InputError as refused:  # the campaign, or every variant, refused: the message says why
            record.update(verdict="REFUSED", why=str(refused)[:500])
        verdict_path = tmp / "run" / "verdict.json"
        if verdict_path.exists():
            verdict = json.loads(verdict_path.read_text())
            held, terms = coverage_of(pd.read_csv(tmp / "run" / verdict["model"] / "calibration.csv"), truth)
            record.update(verdict=verdict["verdict"], model=verdict["model"], held=held, terms=terms,
                          failed=[c["check"] for c in verdict["checks"] if not c["passed"]])
    (Path(out) / f"{index:04d}.json").write_text(json.dumps(record, indent=1))
    return record


def run_battery(n: int, processes: int, out: Path, config_path: Path):
    cfg = yaml.safe_load(config_path.read_text())
    validate(cfg, str(ROOT / "workflow" / "schemas" / "config.schema.yaml"))  # the schema's defaults, as a run's
    out.mkdir(parents=True, exist_ok=True)
    todo = [(i, cfg, out) for i in range(n) if not (out / f"{i:04d}.json").exists()]
    with Pool(processes) as pool:
        for record in pool.imap_unordered(one, todo):
            print(json.dumps(record), flush=True)


def summary(out: Path) -> str:
    frame = pd.DataFrame([json.loads(p.read_text()) for p in sorted(out.glob("*.json"))])
    reviewed = frame[frame["verdict"].isin(["GO", "NO-GO"])].copy()
    reviewed["covered"] = reviewed["held"] == reviewed["terms"]
    lines = [f"{len(frame)} campaigns; {len(frame) - len(reviewed)} refused before a verdict", ""]
    lines += ["| rate | k / n | estimate | 95 % interval | target |", "| --- | --- | --- | --- | --- |"]
    for name, given, event, target in (("P(GO \\| some term missed)", ~reviewed["covered"], "GO", "<= 1 %"),
                                       ("P(NO-GO \\| every term covered)", reviewed["covered"], "NO-GO", "<= 10 %")):
        sub = reviewed[given]
        k, n = int((sub["verdict"] == event).sum()), len(sub)
        lo, hi = binomial_interval(k, n) if n else (np.nan, np.nan)
        lines.append(f"| {name} | {k} / {n} | {k / n if n else np.nan:.3f} | [{lo:.3f}, {hi:.3f}] | {target} |")
    lines += ["", "| kind | campaigns | covered | GO | GO while missed | NO-GO while covered |",
              "| --- | --- | --- | --- | --- | --- |"]
    for kind, g in reviewed.groupby("kind"):
        lines.append(f"| {kind} | {len(g)} | {int(g['covered'].sum())} | {int((g['verdict'] == 'GO').sum())} | "
                     f"{int(((g['verdict'] == 'GO') & ~g['covered']).sum())} | "
                     f"{int(((g['verdict'] == 'NO-GO') & g['covered']).sum())} |")
    wrong_no_go = reviewed[(reviewed["verdict"] == "NO-GO") & reviewed["covered"]]
    reasons = Counter(check for failed in wrong_no_go["failed"] for check in failed)
    lines += ["", "Checks failed on NO-GO with every term covered (a campaign may fail several):"]
    lines += [f"- {check}: {count}" for check, count in reasons.most_common()] or ["- none"]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    go = sub.add_parser("run", help="simulate and run the campaigns not yet recorded in OUT")
    go.add_argument("--n", type=int, default=200)
    go.add_argument("--processes", type=int, default=2)
    go.add_argument("--out", type=Path, required=True)
    go.add_argument("--config", type=Path, default=ROOT / "config" / "config.yaml")
    table = sub.add_parser("summary", help="the tables of the records in OUT")
    table.add_argument("out", type=Path)
    args = parser.parse_args(argv)
    if args.command == "run":
        run_battery(args.n, args.processes, args.out, args.config)
    print(summary(args.out))


if __name__ == "__main__":
    sys.exit(main())
