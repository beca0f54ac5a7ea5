from gyrocal.steps import classic, common, preprocess, validate

o = snakemake.output
common.start(snakemake.log[0])
with common.refusal():
    validate.run(snakemake.params.campaign_dir, o.checked)
maneuvers = preprocess.run(snakemake.params.campaign_dir, o.checked, o.preprocessed, processes=snakemake.threads)
classic.run(maneuvers, o.classic)
common.finish()
