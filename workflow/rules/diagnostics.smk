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
