"""How often the preprocessing's choice of the reference error's clock (``star_tracker: gm_clock_s_per_rad:
auto``, `gyrocal.inference.clock`) finds an angle clock where the simulated error runs on one, and how often
it finds one where the error runs on time or is white (issue 42: the clock's detection rate).

Each campaign is the tiny one (``tests/data/tiny.yaml``, its first ``--maneuvers`` maneuvers; 5 and 20 arcsec
white) with a Gauss-Markov part of each sd across and about the boresight: on the angle clock of 3000 s/rad
(tau 3000 clock seconds: a correlation angle of 1 rad), on time (tau 30 s), or none. The campaign states its
white noise, as campaign.yaml would; ``--campaigns`` seeds each.

    python studies/clock_detection.py [--campaigns 5] [--maneuvers 2] [--sigmas 10 30]
"""

import argparse
from collections import Counter
from pathlib import Path

import yaml

from gyrocal.inference import clock
from gyrocal.inference.noise.covariance import noise_knowledge
from gyrocal.io.scenario import load_scenario
from gyrocal.maneuvers import preprocess
from gyrocal.simulation.simulate import simulate

ROOT = Path(__file__).resolve().parents[1]
ANGLE = {"gm_tau_s": 3000.0, "gm_clock_s_per_rad": 3000.0}
TIME = {"gm_tau_s": 30.0, "gm_clock_s_per_rad": 0.0}


def chosen_clock(gm: dict, seed: int, n_maneuvers: int) -> tuple:
    """The clock chosen on one simulated campaign, and the angle clock's best gain over time."""
    scenario = load_scenario(ROOT / "tests/data/tiny.yaml")
    scenario["star_tracker"].update(gm)
    campaign, _ = simulate(scenario, seed)
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers[:n_maneuvers]]
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    choice = clock.choose(maneuvers, stated)
    return choice.clock_s_per_rad, max(row["gain_over_time"] for row in choice.grid)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--campaigns", type=int, default=5)
    parser.add_argument("--maneuvers", type=int, default=2)
    parser.add_argument("--sigmas", type=float, nargs="+", default=[10.0, 30.0])
    args = parser.parse_args()
    cases = [(f"angle clock 3000 s/rad, {s:g} arcsec", {**ANGLE, "gm_sigma_cross_arcsec": s, "gm_sigma_about_arcsec": s})
             for s in args.sigmas]
    cases += [(f"time, tau 30 s, {s:g} arcsec", {**TIME, "gm_sigma_cross_arcsec": s, "gm_sigma_about_arcsec": s})
              for s in args.sigmas]
    cases.append(("white (no Gauss-Markov part)", {}))
    print(f"| simulated reference error ({args.maneuvers} tiny maneuvers) | n | an angle clock chosen | clocks chosen "
          "(s/rad: count) | best angle gain over time (log-likelihood units) |")
    print("| --- | --- | --- | --- | --- |")
    for label, gm in cases:
        runs = [chosen_clock(gm, seed, args.maneuvers) for seed in range(1, args.campaigns + 1)]
        counts = Counter(k for k, _ in runs)
        gains = ", ".join(f"{g:.1f}" for _, g in runs)
        print(f"| {label} | {len(runs)} | {sum(k > 0 for k, _ in runs)} | "
              f"{', '.join(f'{k:g}: {n}' for k, n in sorted(counts.items()))} | {gains} |", flush=True)


if __name__ == "__main__":
    main()
