rule fleet:
    """Every campaign of a fleet side by side: the reviewed model's parameters and the verdicts."""
    input:
        verdicts=expand(PATHS.verdict, campaign=CAMPAIGNS),
        calibrations=expand(MODEL.calibration, campaign=CAMPAIGNS, model=MODELS),
    output:
        table=f"{results_of('fleet')}/summary.csv",
        figure=report(f"{results_of('fleet')}/summary.png", caption="../report/fleet.rst", category="Fleet"),
    conda:
        "../envs/gyrocal.yaml"
    log:
        "logs/fleet.log",
    benchmark:
        "logs/fleet.benchmark.tsv",
    script:
        "../scripts/fleet.py"
