from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import ExtendSettings
from gyrocal.pipeline.steps import common, extend

p, name = snakemake.params, snakemake.wildcards.extension
paths = CampaignPaths(p.results)
common.start(snakemake.log[0])
with common.refusal():
    extend.run(paths, p.maneuvers, p.models, name, ExtendSettings(**p.settings), placeholders=True)
common.finish()
