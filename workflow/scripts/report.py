from gyrocal.io.outputs import MODEL_FILES
from gyrocal.pipeline.steps import common, report
from gyrocal.pipeline.steps import compare_models as compare

i, p, o = snakemake.input, snakemake.params, snakemake.output
common.start(snakemake.log[0])
compare.run(p.models, i.loo, i.diagnostics, i.summary, i.elpd, p.config["model_choice"], o.table, o.figure)
report.run(p.models, {name: list(getattr(i, name)) for name in MODEL_FILES}, p.maneuvers,
           p.tables, i.checked, o.table, i.truth[0] if i.truth else None, p.config,
           o.html, o.verdict, snakemake.threads)
common.finish()
