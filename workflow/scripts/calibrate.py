from gyrocal.steps import calibrate, common

common.start(snakemake.log[0])
calibrate.run(snakemake.input.point, snakemake.input.summary, snakemake.params.maneuvers,
              snakemake.output.calibration, snakemake.output.correction)
