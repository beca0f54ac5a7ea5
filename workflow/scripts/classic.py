from gyrocal.steps import classic, common

common.start(snakemake.log[0])
classic.run(snakemake.params.maneuvers, snakemake.output[0])
