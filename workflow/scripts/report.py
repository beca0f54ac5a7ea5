from gyrocal.pipeline.settings import ModelChoiceSettings, ReportSettings
from gyrocal.pipeline.steps import common, compare_models, report

i, o, p = snakemake.input, snakemake.output, snakemake.params
common.start(snakemake.log[0])
with common.refusal():
    compare_models.run(p.models, i, o.table, o.figure, ModelChoiceSettings.of(p.settings))
    report.run(p.models, i, i.preprocessed, p.maneuvers, i.checked, o.table, o.html, o.verdict, ReportSettings(p.settings),
               i.truth[0] if i.truth else None, snakemake.threads, dict(zip(p.extended, i.extension)))
common.finish()
