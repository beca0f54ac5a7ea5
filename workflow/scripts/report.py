from gyrocal.outputs import MODEL_FILES
from gyrocal.steps import common, report

i, p = snakemake.input, snakemake.params
common.start(snakemake.log[0])
report.run(p.models, {name: list(getattr(i, name)) for name in MODEL_FILES}, p.maneuvers,
           p.tables, i.checked, i.comparison, i.truth[0] if i.truth else None, p.config,
           snakemake.output.html, snakemake.output.verdict, snakemake.threads)
