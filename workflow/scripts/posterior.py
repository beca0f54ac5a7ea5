from gyrocal.pipeline.steps import calibrate, common, posterior

p, o = snakemake.params, snakemake.output
common.start(snakemake.log[0])
with common.refusal():
    posterior.run(p.maneuvers, snakemake.input.point, snakemake.input.plugins, p.priors,
                  snakemake.input.prior_from[0] if snakemake.input.prior_from else None, p.sampler, p.grid,
                  p.convergence, p.seed, o.posterior, o.summary, o.fit, o.sampler, o.elpd, o.loo)
calibrate.run(snakemake.input.point, o.summary, p.maneuvers, o.calibration, o.correction)
common.finish()
