from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import DiagnosticsSettings
from gyrocal.pipeline.steps import common, diagnostics

p = snakemake.params
common.start(snakemake.log[0])
with common.refusal():
    diagnostics.run(CampaignPaths(p.results), p.maneuvers, snakemake.wildcards.model, DiagnosticsSettings(**p.settings))
common.finish()
