from gyrocal.outputs import MODEL_FILES
from gyrocal.steps import common, report

i = snakemake.input
common.start(snakemake.log[0])
report.run(snakemake.params.models, {name: list(getattr(i, name)) for name in MODEL_FILES}, i.maneuvers,
           i.tables, i.checked, i.comparison, i.truth[0] if i.truth else None, snakemake.params.config,
           snakemake.output.html, snakemake.output.verdict, snakemake.threads)
