from gyrocal.pipeline.steps import common, diagnostics

common.start(snakemake.log[0])
diagnostics.run(snakemake.params.maneuvers, snakemake.input.point, snakemake.input.summary,
                snakemake.input.fit, snakemake.input.plugins, snakemake.params.thresholds,
                snakemake.output[0])
common.finish()
