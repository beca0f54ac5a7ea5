from gyrocal.pipeline.paths import maneuver_files
from gyrocal.pipeline.settings import PosteriorSettings
from gyrocal.pipeline.steps import calibrate, common, posterior

i, o, p, model = snakemake.input, snakemake.output, snakemake.params, snakemake.wildcards.model
common.start(snakemake.log[0])
npz = maneuver_files(i.preprocessed, p.maneuvers)


def run():
    settings = PosteriorSettings(**p.settings)
    posterior.run(npz, i.point, o, settings)
    calibrate.run(npz, i.point, o.summary, o.calibration, o.correction, settings.plugins)


common.variant_step(p.refusal, model, "posterior", run, o)
common.finish()
