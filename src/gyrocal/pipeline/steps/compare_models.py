"""Step ``compare`` (run by the report rule's job): the model variants side by side, and which one is reviewed."""

import pandas as pd

from gyrocal.criticism import comparison
from gyrocal.io.outputs import write_csv, write_with
from gyrocal.pipeline.steps.common import read_json
from gyrocal.report import figures as plots


def run(models, loo_paths, diagnostics_paths, summary_paths, elpd_paths, choice_cfg, out_csv, out_png):
    """``model_comparison.csv``: residual RMS, PSIS-LOO (each model's ``elpd_blocks.csv``) and exact
    leave-one-maneuver-out per variant, what moved, which variants are plausible and which one is
    reviewed."""
    table = comparison.compare(models, [pd.read_csv(p) for p in loo_paths],
                               [read_json(p) for p in diagnostics_paths],
                               [pd.read_csv(p).set_index("label") for p in summary_paths],
                               [pd.read_csv(p)["elpd"].to_numpy() for p in elpd_paths], choice_cfg["reject_se"])
    write_csv(table, out_csv)
    fig = plots.comparison_figure(table)
    write_with(lambda handle: plots.save(fig, handle), out_png)
