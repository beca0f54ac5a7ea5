from gyrocal.pipeline.steps import common, point_estimate

common.start(snakemake.log[0])
point_estimate.run(snakemake.params.maneuvers, snakemake.input.checked, snakemake.wildcards.model,
                   snakemake.params.effects, snakemake.params.noise, snakemake.input.plugins, snakemake.output[0])
common.finish()
