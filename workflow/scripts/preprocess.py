from gyrocal.io import telemetry
from gyrocal.pipeline.paths import maneuver_files
from gyrocal.pipeline.steps import classic, common, preprocess, validate

i, o, p = snakemake.input, snakemake.output, snakemake.params
common.start(snakemake.log[0])
with common.refusal():
    campaign = telemetry.read_campaign(p.campaign_dir)
    validate.run(p.campaign_dir, o.checked, campaign, p.block_s)
    ids = preprocess.run(p.campaign_dir, o.checked, o.preprocessed, processes=snakemake.threads, campaign=campaign,
                         reference_interval_s=p.reference_interval_s, noise=p.noise)
    classic.run(maneuver_files(o.preprocessed, ids), o.checked, o.classic, p.noise)
common.finish()
