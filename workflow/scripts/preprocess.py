from gyrocal.steps import common, preprocess

common.start(snakemake.log[0])
preprocess.run(snakemake.params.campaign_dir, snakemake.input.checked, snakemake.output[0], processes=snakemake.threads)
