from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import PosteriorSettings
from gyrocal.pipeline.steps import calibrate, common, posterior

p, model = snakemake.params, snakemake.wildcards.model
paths = CampaignPaths(p.results)
common.start(snakemake.log[0])


def run():
    posterior.run(paths, p.maneuvers, model, PosteriorSettings(**p.settings))
    calibrate.run(paths, p.maneuvers, model)


common.variant_step(paths, model, "posterior", run, snakemake.output)
common.finish()
