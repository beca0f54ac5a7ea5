from gyrocal import steps

steps.start(snakemake.log[0])
steps.run_preprocess(snakemake.params.campaign_dir, snakemake.input.checked, snakemake.wildcards.maneuver,
                     snakemake.output.data, snakemake.output.table, snakemake.output.figure)
