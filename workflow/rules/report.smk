rule report:
    """The model variants side by side (residual RMS, PSIS-LOO, exact leave-one-maneuver-out),
    which are plausible and which one is reviewed; then the pre-uplink review of that one:
    verdict, the paper's tables with intervals, fits, correction. One job (the steps stay apart
    in gyrocal.pipeline.steps: compare, report), since the comparison takes a fraction of a second and a
    job's start-up more. It shows the whole config, so it alone takes all of it. Its figures
    are drawn in parallel: it ends the run, when nothing else is left to use the cores."""
    input:
        unpack(report_model_files),
        loo=model_files("elpd_blocks.csv"),
        summary=model_files("posterior_summary.csv"),
        elpd=model_files("elpd_maneuvers.csv"),
        preprocessed=PREPROCESSED,
        checked=f"{RESULTS}/input.json",
        truth=truth_input,
    output:
        table=report(f"{RESULTS}/model_comparison.csv", caption="../report/comparison.rst",
                     category="Model comparison"),
        figure=report(f"{RESULTS}/model_comparison.png", caption="../report/comparison.rst",
                      category="Model comparison"),
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
