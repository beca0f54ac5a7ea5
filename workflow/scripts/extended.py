from gyrocal.pipeline.paths import maneuver_files
from gyrocal.pipeline.settings import ExtendSettings
from gyrocal.pipeline.steps import common, extend

i, o, p = snakemake.input, snakemake.output, snakemake.params
common.start(snakemake.log[0])
with common.refusal():
    extend.run(snakemake.wildcards.extension, p.bases, i, maneuver_files(i.preprocessed, p.maneuvers), i.checked, o,
               p.refusal, ExtendSettings(**p.settings))
common.finish()
