from gyrocal import steps

steps.start(snakemake.log[0])
steps.run_classic(snakemake.input.maneuvers, snakemake.output[0])
