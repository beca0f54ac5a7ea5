from gyrocal import steps

steps.start(snakemake.log[0])
steps.run_point_estimate(snakemake.input.maneuvers, snakemake.input.checked, snakemake.input.classic,
                         snakemake.wildcards.model, snakemake.params.effects, snakemake.params.noise,
                         snakemake.input.plugins, snakemake.output[0])
