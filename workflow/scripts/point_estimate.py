from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import PointEstimateSettings
from gyrocal.pipeline.steps import common, point_estimate

p, model = snakemake.params, snakemake.wildcards.model
paths = CampaignPaths(p.results)
common.start(snakemake.log[0])
common.variant_step(paths, model, "point_estimate",
                    lambda: point_estimate.run(paths, p.maneuvers, model, PointEstimateSettings(**p.settings)),
                    snakemake.output)
common.finish()
