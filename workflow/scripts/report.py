from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import ModelChoiceSettings, ReportSettings
from gyrocal.pipeline.steps import common, compare_models, report

p, i = snakemake.params, snakemake.input
paths = CampaignPaths(p.results)
common.start(snakemake.log[0])
with common.refusal():
    compare_models.run(paths, p.models, ModelChoiceSettings.of(p.settings))
    report.run(paths, p.maneuvers, p.models, ReportSettings(p.settings), i.truth[0] if i.truth else None, snakemake.threads)
common.finish()
