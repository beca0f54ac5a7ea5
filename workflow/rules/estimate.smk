rule point_estimate:
    """The full-trajectory weighted least squares of one model, started from the classic estimate
    (computed in the job again: it takes a tenth of a second)."""
    input:
        preprocessed=PATHS.preprocess,
        checked=PATHS.input_json,
        plugins=PLUGINS,
    output:
        point_estimate=MODEL.point_estimate,
    params:
        maneuvers=maneuver_ids,
        refusal=MODEL.refusal,  # the variant's refusal record, where a step refuses it (not always written)
        settings=point_estimate_settings,
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/{{model}}/point_estimate.log",
    benchmark:
        f"{LOGS}/{{model}}/point_estimate.benchmark.tsv",
    script:
        "../scripts/point_estimate.py"
