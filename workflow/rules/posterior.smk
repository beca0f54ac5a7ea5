rule posterior:
    """emcee over the model's parameters and noise scales; convergence across ensembles; then
    calibration.csv per the contract and the gyro correction for every channel set, which need
    nothing but the posterior and no setting (a tenth of a second, in the same job; the steps stay
    apart in gyrocal.pipeline.steps: posterior, calibrate)."""
    input:
        preprocessed=PATHS.preprocess,
        point=MODEL.point_estimate,
        plugins=PLUGINS,
        prior_from=[config["prior_from"]] if config["prior_from"] else [],
    output:
        posterior=MODEL.posterior,
        summary=MODEL.summary,
        fit=MODEL.fit,
        sampler=MODEL.sampler,
        elpd_maneuvers=MODEL.elpd_maneuvers,
        elpd_blocks=MODEL.elpd_blocks,
        orthogonality=MODEL.orthogonality,
        calibration=report(
            MODEL.calibration,
            caption="../report/calibration.rst",
            category="Calibration",
            subcategory="{model}",
        ),
        correction=MODEL.correction,
    params:
        maneuvers=maneuver_ids,
        refusal=MODEL.refusal,
        settings=settings("posterior"),
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/{{model}}/posterior.log",
    benchmark:
        f"{LOGS}/{{model}}/posterior.benchmark.tsv",
    script:
        "../scripts/posterior.py"
