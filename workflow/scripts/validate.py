from gyrocal.steps import common, validate

common.start(snakemake.log[0])
with common.refusal():
    validate.run(snakemake.params.campaign_dir, snakemake.output[0])
