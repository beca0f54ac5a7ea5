from gyrocal.pipeline.steps import common, fleet

common.start(snakemake.log[0])
with common.refusal():
    fleet.run(snakemake.input.verdicts, snakemake.output.table, snakemake.output.figure)
common.finish()
