from gyrocal.steps import common, preprocess, validate

common.start(snakemake.log[0])
with common.refusal():
    validate.run(snakemake.params.campaign_dir, snakemake.output.checked)
preprocess.run(snakemake.params.campaign_dir, snakemake.output.checked, snakemake.output.preprocessed,
               processes=snakemake.threads)
