from gyrocal.pipeline.steps import common
from gyrocal.study import steps as study

common.start(snakemake.log[0])
with common.refusal():
    study.run_chunk(snakemake.params.scenario, snakemake.params.calibration, snakemake.params.study,
                    snakemake.wildcards.group, snakemake.params.indices, snakemake.output[0])
common.finish()
