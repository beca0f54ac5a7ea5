rule point_estimate:
    """The full-trajectory weighted least squares of one model, started from the classic estimate
    (computed in the job again: it takes a tenth of a second)."""
    input:
        preprocessed=PREPROCESSED,
        checked=f"{RESULTS}/input.json",
        plugins=PLUGINS,
    output:
        f"{RESULTS}/{{model}}/point_estimate.npz",
    params:
        maneuvers=maneuver_files("npz"),
        effects=model_effects,
        noise=section("noise"),
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/{{model}}/point_estimate.log",
    benchmark:
        f"{LOGS}/{{model}}/point_estimate.benchmark.tsv",
    script:
        "../scripts/point_estimate.py"
