from gyrocal import steps

steps.log_to(snakemake.log[0])
steps.validate(snakemake.params.campaign_dir, snakemake.output[0])
