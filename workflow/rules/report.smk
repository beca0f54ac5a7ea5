rule report:
    """The pre-uplink review: verdict, the paper's tables with intervals, fits, correction.
    It shows the whole config, so it alone takes all of it. Its figures are drawn in
    parallel: it ends the run, when nothing else is left to use the cores."""
    input:
        unpack(report_model_files),
        preprocessed=PREPROCESSED,
        checked=f"{RESULTS}/input.json",
        comparison=f"{RESULTS}/model_comparison.csv",
        truth=truth_input,
    output:
        html=report(f"{RESULTS}/report.html", caption="../report/review.rst", category="Review before uplink"),
        verdict=f"{RESULTS}/verdict.json",
    params:
        maneuvers=maneuver_files("npz"),
        tables=maneuver_files("csv"),
        config=section(),
        models=MODELS,
    threads: 2
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/report.log",
    benchmark:
        f"{LOGS}/report.benchmark.tsv",
    script:
        "../scripts/report.py"
