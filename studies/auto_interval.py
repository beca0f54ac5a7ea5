"""What ``reference_interval_s: auto`` chooses on the validation study's kinds of campaign.

    python studies/auto_interval.py                 # 20 campaigns per kind, a few minutes
    python studies/auto_interval.py --n 50

Every kind of campaign the validation study and the Gauss-Markov validation fly, with truths drawn
from the configured prior as they are: clean; each hidden effect of ``config/study.yaml`` at its
largest magnitude (on its own scenario); white plus Gauss-Markov star-tracker noise with tau 3 and
30 s (`gauss_markov.scenario_for`). Per campaign, `gyrocal.inference.interval.choose` on its
maneuvers sliced at every sample, as the preprocess step calls it. Printed per kind: how many
campaigns needed the pilot fit (their nominal error was smooth), how many were thinned (the interval
chosen was not 0), and the time of the choice. A campaign neither fitted nor thinned gets exactly
the numbers it got before ``auto`` existed.
"""

import argparse
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]


def kinds(study: dict) -> list:
    """(name, scenario path, hidden simulator keys, tau of the Gauss-Markov noise or None) per kind."""
    out = [("clean", ROOT / study["scenario"], {}, None)]
    for name, effect in study["effects"].items():
        out.append((f"{name} at {max(effect['magnitudes']):g}", ROOT / effect.get("scenario", study["scenario"]),
                    {effect["simulator_key"]: float(max(effect["magnitudes"]))}, None))
    out += [(f"Gauss-Markov tau {tau:g} s", None, {}, tau) for tau in (3.0, 30.0)]
    return out


def one(kind, index: int, cfg: dict, study: dict) -> tuple:
    """(fitted, interval_s, seconds) of campaign ``index`` of ``kind``."""
    from gauss_markov import scenario_for

    from gyrocal.inference import interval
    from gyrocal.maneuvers import preprocess
    from gyrocal.simulation import simulate
    from gyrocal.study.campaign import campaign_scenario, draw_truth, prior_spec

    _, path, hidden, tau = kind
    rng = np.random.default_rng([int(study["seed"]), index])
    if tau is None:
        base = simulate.load_scenario(path)
        truth = draw_truth(prior_spec(simulate.scenario_channels(base), cfg["priors"]), rng)
        scenario = campaign_scenario(base, truth, hidden, f"auto_{index}", int(study["seed"]) * 100003 + index)
    else:
        base = simulate.load_scenario(ROOT / "tests/data/hidden_st_correlated_noise.yaml")
        truth = draw_truth(prior_spec(simulate.scenario_channels(base), cfg["priors"]), rng)
        scenario = scenario_for(tau, index, truth)
    campaign, _ = simulate.simulate(scenario)
    st = scenario["star_tracker"]
    stated = {"sigma_cross_arcsec": float(np.hypot(st["sigma_cross_arcsec"], st.get("gm_sigma_cross_arcsec", 0.0))),
              "sigma_about_arcsec": float(np.hypot(st["sigma_about_arcsec"], st.get("gm_sigma_about_arcsec", 0.0))),
              "boresight_body": st["boresight_body"], "arw_deg_sqrt_h": scenario["gyro"]["arw_deg_sqrt_h"]}
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    start = time.perf_counter()
    choice = interval.choose(maneuvers, stated, scenario.get("gyro", {}).get("sensor_class"))
    return choice.fitted, choice.interval_s, time.perf_counter() - start


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=20, help="campaigns per kind")
    args = parser.parse_args(argv)
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    study = yaml.safe_load((ROOT / "config/study.yaml").read_text())
    print("| kind | campaigns | pilot fit made | thinned | intervals chosen | choice, median ms |")
    print("| --- | --- | --- | --- | --- | --- |")
    for kind in kinds(study):
        rows = [one(kind, i, cfg, study) for i in range(args.n)]
        fitted = sum(r[0] for r in rows)
        chosen = sorted({r[1] for r in rows if r[1]})
        thinned = sum(1 for r in rows if r[1])
        print(f"| {kind[0]} | {args.n} | {fitted} | {thinned} | {', '.join(f'{c:g} s' for c in chosen) or '-'} | "
              f"{1000 * np.median([r[2] for r in rows]):.0f} |", flush=True)


if __name__ == "__main__":
    main()
