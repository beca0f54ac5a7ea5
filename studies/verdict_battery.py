"""The verdict's error rates both ways (docs/validation.md, "The verdict's error rates"): a battery of
simulated campaigns mixing right and wrong models, each through every step of a run with the
default config, its verdict set against whether the reviewed model's intervals hold the truth.

    python studies/verdict_battery.py run --n 200 --processes 2 --out OUT      # records, one JSON a campaign
    python studies/verdict_battery.py summary OUT                             # the tables
    python studies/verdict_battery.py run --n 200 --loop-depth 0 --kinds sf_nonlinearity,st_latency --out GUARD
                                                                              # the guard alone: wrong models

Each campaign flies the tiny test scenario (six DTG channels, five minutes a maneuver pair) with a
truth drawn afresh, and one of the kinds below: clean, large misalignments, Gauss-Markov reference
noise (3 s or 30 s), a bias ramp, a scale-factor nonlinearity, a timing offset the default models
lack, or eigen-axis slews in place of single-axis ones. Whether a model is right is not assumed from
the kind: each record holds every channel term's z = (mean - truth) / sd and 95 % interval in the
reviewed model's ``calibration.csv``, and the summary judges the answer two ways:

- family-wise (the decision's definition): "wrong" when some term's |z| exceeds the Sidak threshold
  that a right answer's m terms all stay within 95 % of the time (3.07 sd for 24 terms), else "right";
- per term (for transparency): "missed" when some term's truth lies outside its own 95 % interval,
  which 1 - 0.95^24 = 71 % of right answers with 24 terms do.

Prints P(GO | wrong) and P(NO-GO | right) under each, with Clopper-Pearson intervals, P(NO-GO | right)
also without the NO-GO on precision alone (`PRECISION`: a right answer wider than the stated
requirement), and P(NO-GO | right and as precise as required), where the precision check passed:
a right answer wider than the requirement gets NO-GO by the requirement's own definition, so this row
asks whether the verdict refuses an answer that is right and usable. Its denominator holds only the
kinds whose right answers meet the requirement (on the tiny scenario's 60-s holds no Gauss-Markov
campaign does), and the rows before it stay, each with its target. Then the checks behind each NO-GO
on a right answer. Each record keeps the loop's depth it ran with (``--loop-depth``); asserts nothing.
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
from scipy import stats as sps
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
    "eigen_axis": ({"maneuvers": [{"id": f"{name}_{sign}", "axis": [float(a / np.sqrt(3.0)) for a in axis],
                                   "direction": "+" if sign == "pos" else "-"}
                                  for name, axis in (("ppp", (1, 1, 1)), ("pmm", (1, -1, -1)),
                                                     ("mpm", (-1, 1, -1)), ("mmp", (-1, -1, 1)))
                                  for sign in ("pos", "neg")]}, 100.0),
}
"""The battery's kinds of campaign, flown in turn: campaign i is kind ``i mod 8`` in name order.
``eigen_axis`` turns 90 deg each way about the four tetrahedron corners (as config/scenarios/mom_eigen.yaml),
so its campaign has no axis labels (free motion)."""

SF_SD_PPM = 1000.0
"""Scale factors drawn N(0, 1000 ppm), as a DTG's residual after ground calibration."""


def kind_of(index: int) -> str:
    """Campaign ``index``'s kind: the kinds in name order, in turn."""
    return sorted(KINDS)[index % len(KINDS)]


def scenario_of(index: int) -> tuple:
    """Campaign ``index``'s scenario (the tiny one with a fresh truth and seed, and its kind's
    changes) and its kind."""
    kind = kind_of(index)
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
        if isinstance(values, list):  # a list (the maneuvers) replaces the tiny scenario's
            scenario[section] = copy.deepcopy(values)
        else:
            scenario.setdefault(section, {}).update(values)
    return scenario, kind


FAMILY_LEVEL = 0.95
"""The family-wise level: a right answer's terms all lie within the threshold this often."""

WRONG_LEVEL = 0.999
"""The family-wise level beyond which an answer is wrong, not unlucky: calibrated intervals put some
term beyond it once in a thousand campaigns (4.10 sd for 24 terms). Between the two thresholds an
answer is neither: calibrated intervals put 5 % of campaigns there, and a verdict, which cannot see
the truth, gives those the GO it gives right answers."""


def family_threshold_sd(terms: int, level: float = FAMILY_LEVEL) -> float:
    """The |z| that ``terms`` independent normal errors all stay within with probability ``level``
    (Sidak: each term's two-sided level is ``level ** (1 / terms)``); 3.07 sd for 24 terms."""
    return float(sps.norm.ppf(0.5 + 0.5 * level ** (1.0 / terms)))


def terms_of(calibration: pd.DataFrame, truth: dict) -> list:
    """Each channel term with a truth: its truth, mean, sd, 95 % interval and z = (mean - truth) / sd."""
    return [{"channel": r.channel, "parameter": r.parameter, "truth": float(truth[r.channel][r.parameter]),
             "mean": float(r.mean), "sd": float(r.sd), "ci95_low": float(r.ci95_low),
             "ci95_high": float(r.ci95_high), "z": float((r.mean - truth[r.channel][r.parameter]) / r.sd)}
            for r in calibration.itertuples() if r.parameter in truth.get(r.channel, {})]


def coverage_of(calibration: pd.DataFrame, truth: dict) -> tuple:
    """How many of the channel terms with a truth lie inside their 95 % interval, and of how many."""
    rows = terms_of(calibration, truth)
    return sum(t["ci95_low"] <= t["truth"] <= t["ci95_high"] for t in rows), len(rows)


def one(args) -> dict:
    """Simulate and run campaign ``index`` with ``cfg``; its record."""
    index, cfg, out = args
    scenario, kind = scenario_of(index)
    record = {"index": index, "kind": kind, "loop_depth": cfg["loop"]["depth"]}
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
            rows = terms_of(pd.read_csv(tmp / "run" / verdict["model"] / "calibration.csv"), truth)
            record.update(verdict=verdict["verdict"], model=verdict["model"],
                          held=sum(t["ci95_low"] <= t["truth"] <= t["ci95_high"] for t in rows), terms=len(rows),
                          max_abs_z=max(abs(t["z"]) for t in rows), family_threshold_sd=family_threshold_sd(len(rows)),
                          failed=[c["check"] for c in verdict["checks"] if not c["passed"]],
                          why={c["check"]: c["why"] for c in verdict["checks"] if not c["passed"]},
                          models=sorted(p.name for p in (tmp / "run").iterdir()
                                        if (p / "calibration.csv").exists()),
                          channel_terms=rows)
    (Path(out) / f"{index:04d}.json").write_text(json.dumps(record, indent=1))
    return record


def campaigns_of(text: str) -> list:
    """The campaign indices a ``--campaigns`` text names: comma-separated indices and ranges, such as
    ``147,150-199`` (a range includes both ends)."""
    indices = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        first, _, last = part.partition("-")
        if not first.isdigit() or (last and not last.isdigit()) or (last and int(last) < int(first)):
            raise ValueError(f"--campaigns: {part!r} is neither an index nor a range such as 150-199")
        indices.extend(range(int(first), int(last or first) + 1))
    return sorted(set(indices))


def run_battery(indices, processes: int, out: Path, config_path: Path, kinds=None, loop_depth=None):
    """Run the campaigns ``indices`` not yet recorded in ``out``, those of ``kinds`` only where given (a
    campaign keeps its index's truth and seed whichever are run); ``loop_depth`` in place of the config's."""
    cfg = yaml.safe_load(config_path.read_text())
    if loop_depth is not None:
        cfg.setdefault("loop", {})["depth"] = loop_depth
    validate(cfg, str(ROOT / "workflow" / "schemas" / "config.schema.yaml"))  # the schema's defaults, as a run's
    cfg["report"]["figures"] = False  # the battery reads verdicts and tables, which no figure changes
    out.mkdir(parents=True, exist_ok=True)
    todo = [(i, cfg, out) for i in indices if not (out / f"{i:04d}.json").exists()
            and (kinds is None or kind_of(i) in kinds)]
    with Pool(processes) as pool:
        for record in pool.imap_unordered(one, todo):
            print(json.dumps(record), flush=True)


PRECISION = "intervals narrow enough"
"""The check that refuses a right answer too wide for the stated requirement (200 ppm, 30 arcsec by
default): a NO-GO on precision, not on a wrong answer."""


def precise_enough_failed(failed: list) -> bool:
    """Whether the precision check is among the checks ``failed``: the answer is wider than the stated
    requirement, so NO-GO is its right verdict whether or not it covers the truth."""
    return PRECISION in failed


def precision_only(failed: list) -> bool:
    """Whether the checks ``failed`` are the precision check alone."""
    return list(failed) == [PRECISION]


def rate_line(name: str, given: pd.Series, verdicts: pd.Series, event: str, target: str) -> str:
    """One row of the rates' table: P(``event`` | ``given``) with its Clopper-Pearson interval."""
    k, n = int((verdicts[given] == event).sum()), int(given.sum())
    if not n:
        return f"| {name} | 0 / 0 | none given | [0, 1] | {target} |"
    lo, hi = binomial_interval(k, n)
    return f"| {name} | {k} / {n} | {k / n:.3f} | [{lo:.3f}, {hi:.3f}] | {target} |"


def rms_z(group: pd.DataFrame) -> str:
    """The root mean square of every recorded term's z in ``group``'s records (1 where the intervals are
    calibrated); empty where no record holds them."""
    z = [t["z"] for terms in group.get("channel_terms", pd.Series(dtype=object)).dropna() for t in terms]
    return f"{np.sqrt(np.mean(np.square(z))):.2f}" if z else ""


def summary(out: Path) -> str:
    frame = pd.DataFrame([json.loads(p.read_text()) for p in sorted(out.glob("*.json"))])
    reviewed = frame[frame["verdict"].isin(["GO", "NO-GO"])].copy()
    reviewed["covered"] = reviewed["held"] == reviewed["terms"]
    if "max_abs_z" not in reviewed:  # records from before the terms' z were kept
        reviewed["max_abs_z"] = np.nan
    has_z = reviewed["max_abs_z"].notna()
    reviewed["right"] = reviewed["max_abs_z"] <= reviewed["terms"].map(family_threshold_sd)
    reviewed["wrong"] = reviewed["max_abs_z"] > reviewed["terms"].map(lambda m: family_threshold_sd(m, WRONG_LEVEL))
    depths = frame["loop_depth"].dropna().astype(int).unique() if "loop_depth" in frame else []
    lines = [f"{len(frame)} campaigns; {len(frame) - len(reviewed)} refused before a verdict; "
             f"{int(has_z.sum())} with every term's z recorded; the loop's depth "
             f"{', '.join(map(str, sorted(depths))) or 'the config default (not recorded)'}"
             + (" (MIXED: records of different depths in one folder)" if len(depths) > 1 else ""), ""]
    lines += ["| rate | k / n | estimate | 95 % interval | target |", "| --- | --- | --- | --- | --- |"]
    fw, verdicts = reviewed[has_z], reviewed["verdict"]
    lines += [rate_line(f"P(GO \\| wrong: some term beyond the family-wise {WRONG_LEVEL:.1%} bound)", fw["wrong"],
                        fw["verdict"], "GO", "<= 1 %"),
              rate_line(f"P(GO \\| some term beyond the family-wise {FAMILY_LEVEL:.0%} bound)", ~fw["right"],
                        fw["verdict"], "GO", "reported (chance puts 5 % of right answers here)"),
              rate_line("P(NO-GO \\| every term within the family-wise bound)", fw["right"], fw["verdict"],
                        "NO-GO", "<= 10 %"),
              rate_line(f"P(NO-GO for more than `{PRECISION}` \\| every term within the family-wise bound)",
                        fw["right"], fw["verdict"].where(~fw["failed"].map(precision_only), "GO"), "NO-GO",
                        "<= 10 %"),
              rate_line("P(NO-GO \\| right and as precise as required: every term within the family-wise bound, "
                        f"`{PRECISION}` passed)", fw["right"] & ~fw["failed"].map(precise_enough_failed),
                        fw["verdict"], "NO-GO", "<= 10 %"),
              rate_line("P(GO \\| some term outside its own 95 % interval) (per term)", ~reviewed["covered"],
                        verdicts, "GO", "<= 1 %"),
              rate_line("P(NO-GO \\| every term inside its own 95 % interval) (per term)", reviewed["covered"],
                        verdicts, "NO-GO", "<= 10 %")]
    lines += ["", "| kind | campaigns | right (family-wise) | wrong (99.9 %) | covered (per term) | GO | "
              "GO while wrong (99.9 %) | GO beyond 95 % | "
              "NO-GO while right | GO while missed (per term) | NO-GO while covered (per term) | "
              "terms outside their 95 % | rms z |",
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for kind, g in reviewed.groupby("kind"):
        go, no_go = g["verdict"] == "GO", g["verdict"] == "NO-GO"
        right = g["right"] & g["max_abs_z"].notna()
        beyond = ~g["right"] & g["max_abs_z"].notna()
        wrong = g["wrong"] & g["max_abs_z"].notna()
        lines.append(f"| {kind} | {len(g)} | {int(right.sum())} | {int(wrong.sum())} | {int(g['covered'].sum())} | "
                     f"{int(go.sum())} | {int((go & wrong).sum())} | {int((go & beyond).sum())} | "
                     f"{int((no_go & right).sum())} | "
                     f"{int((go & ~g['covered']).sum())} | {int((no_go & g['covered']).sum())} | "
                     f"{(g['terms'] - g['held']).sum() / g['terms'].sum():.3f} | {rms_z(g)} |")
    for label, given in (("right (family-wise)", reviewed["right"] & has_z), ("covered (per term)", reviewed["covered"])):
        sub = reviewed[(reviewed["verdict"] == "NO-GO") & given]
        reasons = Counter(check for failed in sub["failed"] for check in failed)
        lines += ["", f"Checks failed on NO-GO with the answer {label} (a campaign may fail several):"]
        lines += [f"- {check}: {count}" for check, count in reasons.most_common()] or ["- none"]
        lines += [f"  - {kind}: " + ", ".join(f"{c} {n}" for c, n in Counter(
            check for failed in g["failed"] for check in failed).most_common()) for kind, g in sub.groupby("kind")]
    wrong_go = reviewed[(reviewed["verdict"] == "GO") & ~reviewed["right"] & has_z]
    bounds = ", ".join(f"{family_threshold_sd(m, WRONG_LEVEL):.2f} sd for {m} terms" for m in sorted(set(reviewed["terms"])))
    lines += ["", f"GO beyond the family-wise {FAMILY_LEVEL:.0%} bound: campaign, kind, model, largest |z| "
              f"(wrong beyond {WRONG_LEVEL:.1%}: {bounds}):"]
    lines += [f"- {r.index:04d} {r.kind} {r.model} {r.max_abs_z:.2f}" for r in wrong_go.itertuples()] or ["- none"]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    go = sub.add_parser("run", help="simulate and run the campaigns not yet recorded in OUT")
    go.add_argument("--n", type=int, default=200, help="run campaigns 0 .. N - 1")
    go.add_argument("--campaigns", type=str, default=None,
                    help="run these campaigns in place of 0 .. N - 1: indices and ranges, such as 147,150-199")
    go.add_argument("--processes", type=int, default=2)
    go.add_argument("--out", type=Path, required=True)
    go.add_argument("--config", type=Path, default=ROOT / "config" / "config.yaml")
    go.add_argument("--kinds", type=lambda text: text.split(","), default=None,
                    help=f"run only these kinds, comma-separated (of {', '.join(sorted(KINDS))})")
    go.add_argument("--loop-depth", type=int, default=None,
                    help="the loop's depth in place of the config's (0: the loop off, so the default models "
                         "face the hidden effects alone: the verdict's guard against wrong answers)")
    table = sub.add_parser("summary", help="the tables of the records in OUT")
    table.add_argument("out", type=Path)
    args = parser.parse_args(argv)
    if args.command == "run":
        unknown = set(args.kinds or ()) - set(KINDS)
        if unknown:
            parser.error(f"--kinds: unknown {sorted(unknown)}; the kinds are {', '.join(sorted(KINDS))}")
        try:
            indices = campaigns_of(args.campaigns) if args.campaigns is not None else range(args.n)
        except ValueError as bad:
            parser.error(str(bad))
        run_battery(indices, args.processes, args.out, args.config, args.kinds, args.loop_depth)
    print(summary(args.out))


if __name__ == "__main__":
    sys.exit(main())
