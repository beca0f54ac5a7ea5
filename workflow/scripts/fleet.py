from gyrocal import steps

steps.start(snakemake.log[0])
steps.run_fleet(snakemake.input.verdicts, snakemake.output.table, snakemake.output.figure)
