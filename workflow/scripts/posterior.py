from gyrocal import steps

steps.log_to(snakemake.log[0])
steps.run_posterior(snakemake.input.maneuvers, snakemake.input.point, snakemake.params.config,
                    snakemake.wildcards.model, snakemake.output.posterior, snakemake.output.summary,
                    snakemake.output.fit, snakemake.output.sampler)
