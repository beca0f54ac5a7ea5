from gyrocal.steps import common, compare

common.start(snakemake.log[0])
compare.run(snakemake.params.models, snakemake.input.loo, snakemake.input.diagnostics,
            snakemake.input.summary, snakemake.input.elpd, snakemake.params.choice, snakemake.output.table,
            snakemake.output.figure)
