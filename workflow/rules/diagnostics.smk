rule diagnostics:
    """Misfit checks of the residuals against the noise model, and what could explain them.
    Ahead of calibrate when both wait for a core: compare needs diagnostics, not calibrate."""
    priority: 1
    input:
        preprocessed=PREPROCESSED,
        point=f"{RESULTS}/{{model}}/point_estimate.npz",
        summary=f"{RESULTS}/{{model}}/posterior_summary.csv",
        fit=f"{RESULTS}/{{model}}/fit.csv",
        plugins=PLUGINS,
    output:
        f"{RESULTS}/{{model}}/diagnostics.json",
    params:
        maneuvers=maneuver_files("npz"),
        thresholds=section("diagnostics"),
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/{{model}}/diagnostics.log",
    benchmark:
        f"{LOGS}/{{model}}/diagnostics.benchmark.tsv",
    script:
        "../scripts/diagnostics.py"


rule compare:
    """Residual RMS, PSIS-LOO and exact leave-one-maneuver-out of every variant; which are plausible."""
    input:
        loo=model_files("elpd_blocks.csv"),
        diagnostics=model_files("diagnostics.json"),
        summary=model_files("posterior_summary.csv"),
        elpd=model_files("elpd_maneuvers.csv"),
    output:
        table=report(f"{RESULTS}/model_comparison.csv", caption="../report/comparison.rst",
                     category="Model comparison"),
        figure=report(f"{RESULTS}/model_comparison.png", caption="../report/comparison.rst",
                      category="Model comparison"),
    params:
        models=MODELS,
        choice=section("model_choice"),
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/compare.log",
    benchmark:
        f"{LOGS}/compare.benchmark.tsv",
    script:
        "../scripts/compare.py"
