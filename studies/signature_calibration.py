"""How often each candidate of the diagnostics' ranking rejects on clean campaigns, against its
nominal rate: the structure test's p-values should be uniform when nothing is missing.

    python studies/signature_calibration.py [--campaigns 24] [--scenario config/scenarios/mom.yaml]

Each campaign draws its truth from the configured prior (as the validation study does), is fitted
with the baseline (classic start, REML noise, WLS) and ranked; no posterior is sampled, so this
is the cheap part of the study's false-alarm table, rerun in minutes after a change.
"""

import argparse
import collections

import numpy as np
import pandas as pd
import yaml
from snakemake.utils import validate

from gyrocal.criticism import diagnostics
from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import point_estimate
from gyrocal.inference.noise import covariance
from gyrocal.maneuvers import preprocess
from gyrocal.model.spec import baseline
from gyrocal.simulation import simulate
from gyrocal.study import campaign as study

ALPHAS = (0.1, 0.01, 0.001)


def ranked(base, cfg, index, seed):
    """log10 p of every candidate on campaign ``index``."""
    rng = np.random.default_rng([seed, index])
    truth = study.draw_truth(study.prior_spec(simulate.scenario_channels(base), cfg["priors"]), rng)
    scenario = study.campaign_scenario(base, truth, {}, f"signature_{index}", seed * 100003 + index)
    campaign, _ = simulate.simulate(scenario)
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    spec = baseline(campaign.channels)
    stated = covariance.noise_knowledge({"star_tracker": scenario["star_tracker"], "gyro": scenario["gyro"]}, cfg["noise"])
    est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    return {r["name"]: r["log10_p"] for r in diagnostics.rank(maneuvers, est, [], ())[0]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--campaigns", type=int, default=24)
    parser.add_argument("--scenario", default="config/scenarios/mom.yaml")
    parser.add_argument("--seed", type=int, default=99)
    args = parser.parse_args()
    with open("config/config.yaml") as handle:
        cfg = yaml.safe_load(handle)
    validate(cfg, "workflow/schemas/config.schema.yaml")
    base = simulate.load_scenario(args.scenario)
    log10_p = collections.defaultdict(list)
    for i in range(args.campaigns):
        for name, value in ranked(base, cfg, i, args.seed).items():
            log10_p[name].append(value)
    rows = [{"candidate": name, "n": len(v), **{f"p<{a:g}": float(np.mean(np.array(v) < np.log10(a))) for a in ALPHAS},
             "min log10 p": min(v)} for name, v in log10_p.items()]
    print(f"{args.campaigns} clean campaigns of {args.scenario}, truths from the prior; nominal rate = alpha")
    print(pd.DataFrame(rows).to_string(index=False, float_format=lambda x: f"{x:.3g}"))


if __name__ == "__main__":
    main()
