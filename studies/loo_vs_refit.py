"""PSIS-LOO against exact refits on the default campaign, and what p_loo counts (issue 12).

    python studies/loo_vs_refit.py [OUT.csv] [--blocks yaw_pos:5,roll_neg:12,...]
    (default OUT: results/study/loo_vs_refit.csv)

Prints figures, asserts nothing. On the default MOM-like campaign (simulated, then gyrocal's
steps up to the baseline posterior), for six 60-s blocks (by default, in yaw_pos, roll_neg and
pitch_pos, the interior holding block and the interior turning block with the largest share of
p_loo: the hardest for importance sampling) it refits without the block (`looexact`: its
star-tracker rows marked invalid, every step rerun) and prints per block: PSIS elpd_i, the
exact elpd_i from the refit's draws, their difference, Pareto k, the exact value's Monte Carlo
error and the block's share of p_loo. Then p_loo against the sum over blocks of the posterior
variances of their terms and of their leverages ``tr(H_i Sigma)``, against the leverages the
blocks would sum to were they independent given the parameters (``tr(A Sigma)``), and against
the 27 sampled parameters; and where the leverage sits (block kind and position, maneuver).

Writes the refit table to OUT and the per-block curvature table to OUT's stem + ``_curvature.csv``.
Each refit runs every step (about 10-20 s on an idle machine); they run one after the other.
"""

import argparse
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd
import yaml

ROOT = Path(__file__).resolve().parents[1]
MANEUVERS = ("yaw_pos", "roll_neg", "pitch_pos")


def default_blocks(table: pd.DataFrame) -> list:
    """Per maneuver of `MANEUVERS`: the interior holding and turning blocks with the largest share
    of p_loo (the least favourable for PSIS, whose weights are widest there)."""
    chosen = []
    for m in MANEUVERS:
        inner = table[(table["maneuver"] == m) & (table["position"] == "interior")]
        for kind in ("holding", "turning"):
            rows = inner[inner["kind"] == kind]
            if len(rows):
                chosen.append(str(rows.loc[rows["psis_p_loo"].idxmax(), "block"]))
    return chosen


def main():
    from snakemake.utils import validate

    from gyrocal.simulation import simulate
    from gyrocal.study import looexact

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out", nargs="?", default=str(ROOT / "results/study/loo_vs_refit.csv"))
    parser.add_argument("--blocks", default="", help="comma-separated block names (maneuver:index)")
    args = parser.parse_args()
    out = Path(args.out)
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    validate(cfg, str(ROOT / "workflow/schemas/config.schema.yaml"))
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        simulate.run(ROOT / "config/scenarios/mom.yaml", tmp / "sim")
        campaign = tmp / "sim" / "campaign"
        looexact.run_steps(campaign, tmp / "full", cfg)
        print(f"full run: {time.perf_counter() - start:.0f} s", flush=True)
        full = looexact.FullRun(tmp / "full", cfg)
        curvature = looexact.curvature_table(full)
        summary = looexact.p_loo_summary(full, curvature)
        names = args.blocks.split(",") if args.blocks else default_blocks(curvature)
        results = []
        for i, name in enumerate(names):
            t0 = time.perf_counter()
            r = full.refit(name, campaign, tmp / f"refit{i}")
            results.append(r)
            print(f"refit {name} ({r.kind}): PSIS {r.psis:.3f}, exact {r.exact:.3f} +- {r.exact_mcse:.3f}, "
                  f"k {r.khat:.2f}, rest intact {r.rest_intact} ({time.perf_counter() - t0:.0f} s)", flush=True)
    table = looexact.refit_table(results)
    out.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(out, index=False)
    curvature.to_csv(out.with_name(out.stem + "_curvature.csv"), index=False)

    pd.set_option("display.width", 200)
    print("\nPSIS-LOO against exact refits (elpd_i in nats; difference = PSIS - exact):")
    print(table[["block", "kind", "samples", "psis", "exact", "difference", "exact_mcse", "khat", "psis_p_loo",
                 "leverage", "rest_intact"]].to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    s = summary
    print(f"\np_loo {s['p_loo']:.2f} over {s['blocks']} blocks (max Pareto k {s['khat_max']:.2f}); "
          f"{s['sampled_parameters']} sampled parameters ({s['free_parameters']} channel parameters the data inform "
          "+ 3 noise scales)")
    print(f"  sum_i Var_post log p(y_i | theta, y_-i)      {s['sum_variance']:.2f}   (p_waic; p_loo to first order)")
    print(f"  = sum_i g_i' Sigma g_i + tr((H_i Sigma)^2)/2 {s['score_sum']:.2f} + {s['second_order_sum']:.2f}")
    print(f"  sum_i tr(H_i Sigma)  (its expectation)       {s['trace_sum']:.2f}   = channel parameters "
          f"{s['trace_sum_params']:.2f} + sigma_cross {s['trace_sum_scale']:.2f}")
    print(f"  tr(A Sigma), blocks independent              {s['joint_trace']:.2f}   = channel parameters "
          f"{s['joint_trace_params']:.2f} + sigma_cross {s['joint_trace'] - s['joint_trace_params']:.2f}")
    blocks = curvature[curvature["kind"] != "joint"]
    print("\nwhere the leverage sits (sums over blocks):")
    grouped = blocks.groupby(["position", "kind"])[["psis_p_loo", "variance", "trace", "trace_params"]].sum()
    grouped.insert(0, "blocks", blocks.groupby(["position", "kind"]).size())
    print(grouped.to_string(float_format=lambda v: f"{v:.2f}"))
    joint = curvature[curvature["kind"] == "joint"].set_index("maneuver")
    per = blocks.groupby("maneuver", sort=False)[["psis_p_loo", "trace_params"]].sum()
    per["joint_trace_params"] = joint["trace_params"]
    per["conditional_share"] = per["trace_params"] / per["joint_trace_params"]
    print("\nper maneuver: the blocks' conditional leverage against the maneuver's own (channel parameters):")
    print(per.to_string(float_format=lambda v: f"{v:.2f}"))
    print(f"\nwrote {out} and {out.with_name(out.stem + '_curvature.csv')} ({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    sys.exit(main())
