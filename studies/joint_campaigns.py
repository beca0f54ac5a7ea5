"""The joint consistency test (`gyrocal joint`) on simulated campaigns of one unit: its false-alarm
rate at its level, and its power against a real change of one parameter between the campaigns.

Each pair is two campaigns of the same scenario and truth with different seeds (their own noise,
biases and start attitudes); a third campaign, with the second's seed, has one parameter's truth
moved by ``--shift-sd`` of one campaign's sd. Each campaign is fitted as the point-estimate step
does (the test and the joint fit need no more: the posterior given the noise is Gaussian). For
comparison it also counts how often `gyrocal compare-campaigns`'s parameter-by-parameter rule (some
|z| >= 3) fires, how often the moved parameter leads the largest direction, and the ratio of the
joint fit's sds to one campaign's.

    PYTHONPATH=src python studies/joint_campaigns.py --pairs 50 --processes 2 --out /tmp/joint_study

prints the table and writes ``pairs.csv`` there.
"""

import argparse
import copy
from multiprocessing import Pool
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from scipy import stats

ROOT = Path(__file__).resolve().parents[1]


def fit(scenario: dict, seed: int, reml: bool, cfg: dict):
    """Simulate ``scenario`` at ``seed`` and fit the baseline as the point-estimate step does
    (classic start, WLS; REML noise scales only with ``reml``, else the stated noise, which is the
    simulator's): the campaign's likelihood and its specification with the config's priors."""
    from gyrocal.criticism.joint import CampaignLikelihood
    from gyrocal.inference.fit import classic, estimate
    from gyrocal.inference.noise.covariance import noise_knowledge
    from gyrocal.maneuvers import preprocess
    from gyrocal.model.spec import baseline
    from gyrocal.simulation.simulate import simulate

    campaign, _ = simulate(scenario, seed)
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, cfg["noise"])
    spec = baseline(campaign.channels)
    est = estimate.point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec), reml)
    spec = est.spec.with_priors(cfg["priors"])
    return CampaignLikelihood.of(str(seed), spec, est.theta, est.cov, spec.prior_mean_si, spec.prior_sd_si), spec


def shifted(scenario: dict, label: str, by: float) -> dict:
    """The scenario with one parameter's truth (``channel.parameter``, in its unit) moved by ``by``."""
    out = copy.deepcopy(scenario)
    channel, name = label.split(".")
    out["truth"][channel][name] = out["truth"][channel].get(name, 0.0) + by
    return out


def one_pair(job):
    """The test on (A, B) of one truth and on (A, B shifted); the per-parameter rule on both; the
    joint sd over one campaign's."""
    from gyrocal.criticism.agreement import compare
    from gyrocal.criticism.consistency import consistency
    from gyrocal.criticism.joint import joint_fit, joint_table

    i, scenario, seeds, label, by, reml, cfg = job
    a, spec = fit(scenario, seeds[0], reml, cfg)
    b, _ = fit(scenario, seeds[1], reml, cfg)
    c, _ = fit(shifted(scenario, label, by), seeds[1], reml, cfg)
    prior = (spec.prior_mean_si[spec.core], spec.prior_sd_si[spec.core])
    one = {k: joint_table(spec, joint_fit([lik], *prior)) for k, lik in (("a", a), ("b", b), ("c", c))}
    row = {"pair": i, "seed_a": seeds[0], "seed_b": seeds[1],
           "sd_ratio_joint_to_one": float(np.median(joint_table(spec, joint_fit([a, b], *prior))["sd"] / one["a"]["sd"]))}
    for tag, other in (("null", b), ("shift", c)):
        test = consistency([a.estimate, other.estimate], [a.info, other.info], *prior, a.labels)
        top = test.against_rest[0]["directions"][0].loadings
        row.update({f"chi2_{tag}": test.chi2, f"dof_{tag}": test.dof, f"p_{tag}": test.p_value,
                    f"top_is_{tag}": max(top, key=lambda k: abs(top[k])) == label,
                    f"max_abs_z_{tag}": float(compare(one["a"], one["b" if tag == "null" else "c"])["z"].abs().max())})
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=50)
    parser.add_argument("--scenario", default=str(ROOT / "tests" / "data" / "tiny.yaml"))
    parser.add_argument("--parameter", default="dtg2_yaw.mis_roll", help="the parameter that changes")
    parser.add_argument("--shift-sd", type=float, default=3.0, help="its change, in one campaign's sd")
    parser.add_argument("--level", type=float, default=0.05)
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument("--reml", action="store_true", help="estimate each campaign's noise scales (REML), as a run "
                        "does; default: the stated noise, which is the simulator's (three times as fast)")
    parser.add_argument("--out", default="/tmp/joint_study")
    args = parser.parse_args()
    from gyrocal.io.scenario import load_scenario

    scenario = load_scenario(args.scenario)
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    pilot, spec = fit(scenario, 999, args.reml, cfg)  # one campaign's sd of the parameter, at another seed
    j = spec.index(args.parameter)
    unit = spec.parameters[j].unit
    by = args.shift_sd * float(np.sqrt(np.linalg.inv(pilot.info)[j, j]) / spec.si_per_unit[j])
    jobs = [(i, scenario, (10_000 + 2 * i, 10_001 + 2 * i), args.parameter, by, args.reml, cfg)
            for i in range(args.pairs)]
    with Pool(args.processes) as pool:
        rows = pool.map(one_pair, jobs)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table = pd.DataFrame(rows)
    table.to_csv(out / "pairs.csv", index=False)
    n = len(table)
    summary = pd.DataFrame({
        "case": ["same truth", f"{args.parameter} moved {args.shift_sd:g} sd ({by:.1f} {unit})"],
        "joint test: share with p < level": [(table["p_null"] < args.level).mean(), (table["p_shift"] < args.level).mean()],
        "per-parameter rule: share with max |z| >= 3": [(table["max_abs_z_null"] >= 3).mean(),
                                                         (table["max_abs_z_shift"] >= 3).mean()],
        "moved parameter leads the largest direction": [np.nan, table["top_is_shift"].mean()],
        "mean chi2 / dof": [(table["chi2_null"] / table["dof_null"]).mean(),
                            (table["chi2_shift"] / table["dof_shift"]).mean()]})
    se = np.sqrt(args.level * (1 - args.level) / n)
    print(f"{n} pairs of {scenario['name']}, level {args.level:g} (binomial se of the false-alarm rate {se:.3f}); "
          f"dof {int(table['dof_null'].median())}; joint sd / one campaign's sd, median "
          f"{table['sd_ratio_joint_to_one'].median():.3f} (1/sqrt 2 = 0.707); same truth: p-values against uniform, "
          f"Kolmogorov-Smirnov p = {stats.kstest(table['p_null'], 'uniform').pvalue:.2f}")
    print(summary.to_markdown(index=False, floatfmt=".3f"))


if __name__ == "__main__":
    main()
