"""Detection and false alarms of the reference's timing jitter (`st_jitter`) in the diagnostics' ranking
(issue 42 item 2): the white baseline fitted and ranked (`gyrocal.study.baseline`) on simulated campaigns.

- detection: `tests/data/hidden_st_jitter.yaml` (turns at 5 deg/s, a 5 arcsec tracker) with a jitter of each
  magnitude, ``--campaigns`` seeds each: how often `st_jitter` is ranked first, and how often its own score
  (`rategrowth`, ``whiteness.rate_growth``) has log10 p < -2;
- false alarms: the same campaign without jitter, with a 20 ms latency instead (a latency also grows with
  the rate), and the other hidden cases (`hidden_<case>.yaml`, their own magnitudes): how often `st_jitter` is
  ranked first, and how often its score has log10 p < -2.

    python studies/jitter_detection.py [--campaigns 5] [--magnitudes 0.25 0.5 1 2]
"""

import argparse
from pathlib import Path

import yaml

from gyrocal.simulation import simulate
from gyrocal.study.baseline import baseline_ranking

ROOT = Path(__file__).resolve().parents[1]
OTHER_CASES = ("bias_drift", "st_latency", "sf_nonlinearity", "st_correlated_noise")


def ranked(name: str, seed: int, **effects) -> tuple:
    """`st_jitter`'s place in the ranking (0: first) and its score's log10 p on one simulated campaign."""
    scenario = simulate.load_scenario(ROOT / f"tests/data/hidden_{name}.yaml")
    scenario["effects"].update(effects)
    scenario["seed"] = seed
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    _, _, white, ranking = baseline_ranking(simulate.simulate(scenario)[0], cfg["noise"])
    names = [r["name"] for r in ranking]
    return names.index("st_jitter"), white["rate_growth"]["log10_p"], names[0]


def row(label: str, runs: list) -> str:
    first = sum(place == 0 for place, _, _ in runs)
    significant = sum(p < -2 for _, p, _ in runs)
    leaders = ", ".join(sorted({lead for _, _, lead in runs}))
    return f"| {label} | {len(runs)} | {first} | {significant} | {leaders} |"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--campaigns", type=int, default=5)
    parser.add_argument("--magnitudes", type=float, nargs="+", default=[0.25, 0.5, 1.0, 2.0])
    args = parser.parse_args()
    seeds = range(1, args.campaigns + 1)
    print("| campaign | n | st_jitter ranked first | its score log10 p < -2 | ranked first (all runs) |")
    print("| --- | --- | --- | --- | --- |")
    for ms in args.magnitudes:
        print(row(f"st_jitter {ms:g} ms", [ranked("st_jitter", s, st_jitter_ms=ms) for s in seeds]), flush=True)
    print(row("no jitter (clean, 5 deg/s)", [ranked("st_jitter", s, st_jitter_ms=0.0) for s in seeds]), flush=True)
    print(row("st_latency 20 ms, 5 deg/s", [ranked("st_jitter", s, st_jitter_ms=0.0, st_latency_s=0.02)
                                            for s in seeds]), flush=True)
    for case in OTHER_CASES:
        print(row(f"hidden {case}", [ranked(case, s) for s in seeds]), flush=True)


if __name__ == "__main__":
    main()
