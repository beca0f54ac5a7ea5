"""Command ``gyrocal plan``: predict what planned campaigns will tell, and write the plan's tables
and figure (under ``results/plan/`` unless told otherwise)."""

from pathlib import Path

import pandas as pd

from gyrocal.io.outputs import write_csv, write_with
from gyrocal.planning import plan
from gyrocal.report import figures as plots

__all__ = ["DEFAULT_OUT", "run"]

DEFAULT_OUT = "results/plan"
"""Where ``gyrocal plan`` writes when no ``--out`` is given: beside a run's results, never the
current folder."""


def run(scenario_paths, config_path, out_dir, model: str = "baseline") -> str:
    """``gyrocal plan``: predict each scenario, write plan.csv, plan_detection.csv and plan.png to
    ``out_dir``, and return the printed report."""
    cfg = plan.read_config(config_path)
    scenarios = [plan.read_scenario(p) for p in scenario_paths]
    names = [s["name"] for s in scenarios]
    if len(set(names)) < len(names):
        names = [f"{n}_{tag}" for n, tag in zip(names, "AB")]
    plans = [plan.plan(s, cfg, model, n) for s, n in zip(scenarios, names)]
    out_dir = Path(out_dir)
    write_csv(pd.concat([p.table() for p in plans]), out_dir / "plan.csv")
    write_csv(pd.concat([p.detection.assign(plan=p.name) for p in plans]), out_dir / "plan_detection.csv")
    fig = plan.figure(plans)
    write_with(lambda handle: plots.save(fig, handle), out_dir / "plan.png")
    return plan.report(plans) + f"\nwrote {out_dir}/plan.csv, plan_detection.csv and plan.png"
