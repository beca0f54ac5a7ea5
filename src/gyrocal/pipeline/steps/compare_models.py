"""Step ``compare_models`` (run by the report rule's job): the model variants side by side, and which one is reviewed."""

import pandas as pd

from gyrocal.criticism import comparison
from gyrocal.io.outputs import write_csv, write_with
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import ModelChoiceSettings
from gyrocal.pipeline.steps.common import compared, read_json

__all__ = ["run", "table"]


def table(paths: CampaignPaths, models, reject_se: float) -> pd.DataFrame:
    """The comparison of the variants ``models`` (`gyrocal.criticism.comparison.compare`) from their
    files; a variant refused or skipped (its ``refused.json``) is left out, the first one left is the
    reference."""
    models = compared(paths, models)
    each = [paths.model(m) for m in models]
    return comparison.compare(list(models), [pd.read_csv(m.elpd_blocks) for m in each],
                              [read_json(m.diagnostics) for m in each],
                              [pd.read_csv(m.summary).set_index("label") for m in each],
                              [pd.read_csv(m.elpd_maneuvers)["elpd"].to_numpy() for m in each], reject_se)


def run(paths: CampaignPaths, models, settings: ModelChoiceSettings):
    """``model_comparison.csv``: residual RMS, PSIS-LOO (each model's ``elpd_blocks.csv``) and exact
    leave-one-maneuver-out per variant, what moved, which variants are plausible and which one is
    reviewed (`table`); and its figure."""
    from gyrocal.report import figures as plots  # matplotlib: not for the loop's step, which reads `table` alone

    table_ = table(paths, models, settings.reject_se)
    write_csv(table_, paths.comparison)
    fig = plots.comparison_figure(table_)
    write_with(lambda handle: plots.save(fig, handle), paths.comparison_figure)
