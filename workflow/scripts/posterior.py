from gyrocal import steps

p = snakemake.params
steps.start(snakemake.log[0])
with steps.refusal():
    steps.run_posterior(snakemake.input.maneuvers, snakemake.input.point, snakemake.input.plugins, p.priors,
                        snakemake.input.prior_from[0] if snakemake.input.prior_from else None, p.sampler, p.grid,
                        p.convergence, p.seed, snakemake.output.posterior, snakemake.output.summary,
                        snakemake.output.fit, snakemake.output.sampler, snakemake.output.elpd)
