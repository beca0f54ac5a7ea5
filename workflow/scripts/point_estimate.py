from gyrocal import steps

steps.log_to(snakemake.log[0])
steps.run_point_estimate(snakemake.input.maneuvers, snakemake.params.campaign_dir, snakemake.params.config,
                         snakemake.wildcards.model, snakemake.output.point, snakemake.output.classic)
