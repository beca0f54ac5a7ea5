rule report:
    """The model variants side by side (residual RMS, PSIS-LOO, exact leave-one-maneuver-out),
    which are plausible and which one is reviewed; then the pre-uplink review of that one:
    verdict, the paper's tables with intervals, fits, correction. One job (the steps stay apart
    in gyrocal.pipeline.steps: compare_models, report), since the comparison takes a fraction of a
    second and a job's start-up more. It shows the whole config, so it alone takes all of it. Its
    figures are drawn in parallel: it ends the run, when nothing else is left to use the cores."""
    input:
        **{name: model_files(name) for name in MODEL_FILES},
        extension=[PATHS.model(m).extension for m in EXTENDED],
        preprocessed=PATHS.preprocess,
        checked=PATHS.input_json,
        truth=truth_input,
    output:
        table=report(PATHS.comparison, caption="../report/comparison.rst", category="Model comparison"),
        figure=report(PATHS.comparison_figure, caption="../report/comparison.rst", category="Model comparison"),
        html=report(PATHS.report, caption="../report/review.rst", category="Review before uplink"),
        verdict=PATHS.verdict,
    params:
        maneuvers=maneuver_ids,
        models=MODELS + EXTENDED,
        extended=EXTENDED,
        settings=whole_config(),
    threads: 2
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/report.log",
    benchmark:
        f"{LOGS}/report.benchmark.tsv",
    script:
        "../scripts/report.py"
