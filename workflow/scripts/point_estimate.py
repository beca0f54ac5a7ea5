from gyrocal.pipeline.paths import maneuver_files
from gyrocal.pipeline.settings import PointEstimateSettings
from gyrocal.pipeline.steps import common, point_estimate

i, o, p, model = snakemake.input, snakemake.output, snakemake.params, snakemake.wildcards.model
common.start(snakemake.log[0])
common.variant_step(p.refusal, model, "point_estimate",
                    lambda: point_estimate.run(maneuver_files(i.preprocessed, p.maneuvers), i.checked, o.point_estimate,
                                               model, PointEstimateSettings(**p.settings)),
                    o)
common.finish()
