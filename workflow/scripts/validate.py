from gyrocal import steps

steps.start(snakemake.log[0])
with steps.refusal():
    steps.validate(snakemake.params.campaign_dir, snakemake.output[0])
