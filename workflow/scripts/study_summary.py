from pathlib import Path

from gyrocal.pipeline.steps import common
from gyrocal.study import steps as study

common.start(snakemake.log[0])
with common.refusal():
    study.summarize(snakemake.input.records, snakemake.params.scenario, snakemake.params.calibration, snakemake.params.study,
                    Path(snakemake.output.tables[0]).parent)
common.finish()
