from gyrocal.steps import common, posterior

p = snakemake.params
common.start(snakemake.log[0])
with common.refusal():
    posterior.run(snakemake.params.maneuvers, snakemake.input.point, snakemake.input.plugins, p.priors,
                  snakemake.input.prior_from[0] if snakemake.input.prior_from else None, p.sampler, p.grid,
                  p.convergence, p.seed, snakemake.output.posterior, snakemake.output.summary,
                  snakemake.output.fit, snakemake.output.sampler, snakemake.output.elpd, snakemake.output.loo)
