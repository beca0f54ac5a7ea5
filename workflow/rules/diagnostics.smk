rule diagnostics:
    """Misfit checks of the residuals against the noise model, and what could explain them."""
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
