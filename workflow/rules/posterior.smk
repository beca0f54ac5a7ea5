rule posterior:
    """emcee over the model's parameters and noise scales; convergence across ensembles; then
    calibration.csv per the contract and the gyro correction for every channel set, which need
    nothing but the posterior and no setting (a tenth of a second, in the same job; the steps stay
    apart in gyrocal.pipeline.steps: posterior, calibrate)."""
    input:
        preprocessed=PREPROCESSED,
        point=f"{RESULTS}/{{model}}/point_estimate.npz",
        plugins=PLUGINS,
        prior_from=[config["prior_from"]] if config["prior_from"] else [],
    output:
        posterior=f"{RESULTS}/{{model}}/posterior.nc",
        summary=f"{RESULTS}/{{model}}/posterior_summary.csv",
        fit=f"{RESULTS}/{{model}}/fit.csv",
        sampler=f"{RESULTS}/{{model}}/sampler.json",
        elpd=f"{RESULTS}/{{model}}/elpd_maneuvers.csv",
        loo=f"{RESULTS}/{{model}}/elpd_blocks.csv",
        calibration=report(
            f"{RESULTS}/{{model}}/calibration.csv",
            caption="../report/calibration.rst",
            category="Calibration",
            subcategory="{model}",
        ),
        correction=f"{RESULTS}/{{model}}/correction.json",
    params:
        maneuvers=maneuver_files("npz"),
        priors=section("priors"),
        sampler=section("sampler"),
        grid=section("grid"),
        convergence=section("convergence"),
        seed=config["seed"],
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/{{model}}/posterior.log",
    benchmark:
        f"{LOGS}/{{model}}/posterior.benchmark.tsv",
    script:
        "../scripts/posterior.py"
