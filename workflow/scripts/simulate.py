from gyrocal.pipeline.steps import common
from gyrocal.simulation import simulate

common.start(snakemake.log[0])
with common.refusal():
    simulate.run(snakemake.input.scenario, snakemake.output.campaign.rsplit("/", 1)[0], snakemake.params.seed)
common.finish()
