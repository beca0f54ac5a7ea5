from gyrocal import steps

steps.start(snakemake.log[0])
steps.run_compare(snakemake.params.models, snakemake.input.posterior, snakemake.input.diagnostics,
                  snakemake.input.summary, snakemake.input.elpd, snakemake.params.choice, snakemake.output.table,
                  snakemake.output.figure)
