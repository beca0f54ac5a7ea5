from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import DiagnosticsSettings
from gyrocal.pipeline.steps import common, diagnostics

p, model = snakemake.params, snakemake.wildcards.model
paths = CampaignPaths(p.results)
common.start(snakemake.log[0])
common.variant_step(paths, model, "diagnostics",
                    lambda: diagnostics.run(paths, p.maneuvers, model, DiagnosticsSettings(**p.settings)),
                    snakemake.output)
common.finish()
