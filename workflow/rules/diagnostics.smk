rule diagnostics:
    """Misfit checks of the residuals against the noise model, and what could explain them."""
    input:
        preprocessed=PATHS.preprocess,
        point=MODEL.point_estimate,
        summary=MODEL.summary,
        fit=MODEL.fit,
        plugins=PLUGINS,
    output:
        diagnostics=MODEL.diagnostics,
    params:
        maneuvers=maneuver_ids,
        refusal=MODEL.refusal,
        settings=settings("diagnostics"),
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/{{model}}/diagnostics.log",
    benchmark:
        f"{LOGS}/{{model}}/diagnostics.benchmark.tsv",
    script:
        "../scripts/diagnostics.py"
