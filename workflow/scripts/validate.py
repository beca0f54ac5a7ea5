from gyrocal import steps

steps.start(snakemake.log[0])
steps.validate(snakemake.params.campaign_dir, snakemake.output[0])
