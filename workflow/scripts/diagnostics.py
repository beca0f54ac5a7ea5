from gyrocal import steps

steps.log_to(snakemake.log[0])
steps.run_diagnostics(snakemake.input.maneuvers, snakemake.input.point, snakemake.input.summary,
                      snakemake.input.fit, snakemake.params.config, snakemake.wildcards.model, snakemake.output[0])
