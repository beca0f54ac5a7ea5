from gyrocal.io import telemetry
from gyrocal.pipeline.steps import classic, common, preprocess, validate

o, campaign_dir = snakemake.output, snakemake.params.campaign_dir
common.start(snakemake.log[0])
with common.refusal():
    campaign = telemetry.read_campaign(campaign_dir)
    validate.run(campaign_dir, o.checked, campaign)
maneuvers = preprocess.run(campaign_dir, o.checked, o.preprocessed, processes=snakemake.threads, campaign=campaign)
classic.run(maneuvers, o.classic)
common.finish()
