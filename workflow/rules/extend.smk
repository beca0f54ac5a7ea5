rule extended:
    """The model-criticism loop, one step a job (gyrocal.criticism.extension): where the reviewed model
    misfits and its diagnostics name a library effect significantly, the model extended by it, fitted
    in the same run (point estimate, posterior, calibration, diagnostics, as their rules run them),
    under the fixed variant name extended (extended_<k> for the k-th step, up to loop.depth). Where
    it does not, the variant is skipped with the reason, at the cost of reading the diagnostics."""
    input:
        unpack(extension_input),
        preprocessed=PATHS.preprocess,
        checked=PATHS.input_json,
        plugins=PLUGINS,
    output:
        extension=EXTENDED_MODEL.extension,
        **{name: getattr(EXTENDED_MODEL, name) for name in MODEL_FILES},
    params:
        maneuvers=maneuver_ids,
        bases=extension_bases,
        refusal=EXTENDED_MODEL.refusal,
        settings=extend_settings(),
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/{{extension}}/extended.log",
    benchmark:
        f"{LOGS}/{{extension}}/extended.benchmark.tsv",
    script:
        "../scripts/extended.py"
