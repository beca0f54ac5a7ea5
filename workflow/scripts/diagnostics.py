from gyrocal import steps

steps.start(snakemake.log[0])
steps.run_diagnostics(snakemake.input.maneuvers, snakemake.input.point, snakemake.input.summary,
                      snakemake.input.fit, snakemake.input.plugins, snakemake.params.thresholds,
                      snakemake.output[0])
