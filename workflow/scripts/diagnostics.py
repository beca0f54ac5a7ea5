from gyrocal.pipeline.paths import maneuver_files
from gyrocal.pipeline.settings import DiagnosticsSettings
from gyrocal.pipeline.steps import common, diagnostics

i, o, p, model = snakemake.input, snakemake.output, snakemake.params, snakemake.wildcards.model
common.start(snakemake.log[0])
common.variant_step(p.refusal, model, "diagnostics",
                    lambda: diagnostics.run(maneuver_files(i.preprocessed, p.maneuvers), i.point, i.fit, i.summary,
                                            o.diagnostics, DiagnosticsSettings(**p.settings)),
                    o)
common.finish()
