from gyrocal import steps

steps.log_to(snakemake.log[0])
steps.run_calibrate(snakemake.input.point, snakemake.input.summary, snakemake.input.maneuvers,
                    snakemake.params.config, snakemake.wildcards.model,
                    snakemake.output.calibration, snakemake.output.correction)
