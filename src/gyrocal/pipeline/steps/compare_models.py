"""Step ``compare_models`` (run by the report rule's job): the model variants side by side, and which one is reviewed."""

import pandas as pd

from gyrocal.criticism import comparison
from gyrocal.io.outputs import write_csv, write_with
from gyrocal.pipeline.settings import ModelChoiceSettings
from gyrocal.pipeline.steps.common import compared, read_json

__all__ = ["run", "table"]


def table(models, files, reject_se: float) -> pd.DataFrame:
    """The comparison of the variants ``models`` (`gyrocal.criticism.comparison.compare`): residual RMS,
    PSIS-LOO and exact leave-one-maneuver-out per variant, what moved, which variants are plausible and
    which one is reviewed. ``files``: each model's files by their `ModelPaths` name, a list in the order
    of ``models`` each (``elpd_blocks``, ``diagnostics``, ``summary``, ``elpd_maneuvers``: a rule's
    ``snakemake.input``, or `CampaignPaths.per_model`). A variant refused or skipped (its diagnostics
    hold its refusal record) is left out; the first one left is the reference."""
    kept = compared(models, files.diagnostics)
    each = [list(models).index(m) for m in kept]
    return comparison.compare(kept, [pd.read_csv(files.elpd_blocks[i]) for i in each],
                              [read_json(files.diagnostics[i]) for i in each],
                              [pd.read_csv(files.summary[i]).set_index("label") for i in each],
                              [pd.read_csv(files.elpd_maneuvers[i])["elpd"].to_numpy() for i in each], reject_se)


def run(models, files, out_csv, out_png, settings: ModelChoiceSettings):
    """``out_csv`` (``model_comparison.csv``): the comparison of the variants ``models`` from their
    ``files`` (`table`); and its figure, ``out_png``."""
    from gyrocal.report import figures as plots  # matplotlib: not for the loop's step, which reads `table` alone

    table_ = table(models, files, settings.reject_se)
    write_csv(table_, out_csv)
    fig = plots.comparison_figure(table_)
    write_with(lambda handle: plots.save(fig, handle), out_png)
