from gyrocal import steps

steps.log_to(snakemake.log[0])
steps.run_report(snakemake.params.results, snakemake.params.models, snakemake.input.maneuvers,
                 snakemake.input.truth[0] if snakemake.input.truth else None, snakemake.params.config,
                 snakemake.output[0])
