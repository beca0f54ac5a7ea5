from gyrocal.io import telemetry
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.steps import classic, common, preprocess, validate

paths, campaign_dir = CampaignPaths(snakemake.params.results), snakemake.params.campaign_dir
common.start(snakemake.log[0])
with common.refusal():
    campaign = telemetry.read_campaign(campaign_dir)
    validate.run(campaign_dir, paths, campaign, snakemake.params.block_s)
    ids = preprocess.run(campaign_dir, paths, processes=snakemake.threads, campaign=campaign,
                         reference_interval_s=snakemake.params.reference_interval_s,
                         noise=snakemake.params.noise)
    classic.run(paths, ids, snakemake.params.noise)
common.finish()
