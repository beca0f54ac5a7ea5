from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import PointEstimateSettings
from gyrocal.pipeline.steps import common, point_estimate

p = snakemake.params
common.start(snakemake.log[0])
with common.refusal():
    point_estimate.run(CampaignPaths(p.results), p.maneuvers, snakemake.wildcards.model, PointEstimateSettings(**p.settings))
common.finish()
