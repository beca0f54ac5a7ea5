from pathlib import Path

from gyrocal.steps import common, study

common.start(snakemake.log[0])
study.summarize(snakemake.input.records, snakemake.params.scenario, snakemake.params.calibration, snakemake.params.study,
                Path(snakemake.output.tables[0]).parent)
common.finish()
