rule simulate:
    """The default campaign: a Mars-Orbiter-like simulation whose truth is the paper's tables."""
    input:
        scenario=config["scenario"],
    output:
        campaign=directory(PATHS.simulated),
        truth=PATHS.truth,
    params:
        seed=config["simulation_seed"],
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/simulate.log",
    benchmark:
        f"{LOGS}/simulate.benchmark.tsv",
    script:
        "../scripts/simulate.py"
