from gyrocal import steps

steps.start(snakemake.log[0])
steps.run_calibrate(snakemake.input.point, snakemake.input.summary, snakemake.input.maneuvers,
                    snakemake.output.calibration, snakemake.output.correction)
