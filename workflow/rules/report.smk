rule report:
    """The pre-uplink review: verdict, the paper's tables with intervals, fits, correction."""
    input:
        maneuvers=maneuver_files("npz"),
        tables=maneuver_files("csv"),
        checked=f"{RESULTS}/input.json",
        comparison=f"{RESULTS}/model_comparison.csv",
        models=expand(f"{RESULTS}/{{model}}/{{name}}", model=MODELS,
                      name=["calibration.csv", "diagnostics.json", "sampler.json", "correction.json",
                            "fit.csv", "posterior.nc", "point_estimate.npz"]),
        truth=[f"{config['results']}/{CAMPAIGN}/simulated/truth.json"] if SIMULATED else [],
    output:
        report(f"{RESULTS}/report.html", caption="../report/review.rst", category="Review before uplink"),
    params:
        config=config,
        results=lambda wildcards, input: str(Path(input.comparison).parent),
        models=MODELS,
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/report.log",
    script:
        "../scripts/report.py"
