rule fleet:
    """Every campaign of a fleet side by side: the reviewed model's parameters and the verdicts."""
    input:
        verdicts=expand(f"{config['results']}/{{campaign}}/verdict.json", campaign=CAMPAIGNS),
        calibrations=expand(f"{config['results']}/{{campaign}}/{{model}}/calibration.csv", campaign=CAMPAIGNS,
                            model=MODELS),
    output:
        table=f"{config['results']}/fleet/summary.csv",
        figure=report(f"{config['results']}/fleet/summary.png", caption="../report/fleet.rst", category="Fleet"),
    conda:
        "../envs/gyrocal.yaml"
    log:
        "logs/fleet.log",
    script:
        "../scripts/fleet.py"
