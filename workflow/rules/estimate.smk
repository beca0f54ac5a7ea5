rule point_estimate:
    """The paper's classic estimate and the full-trajectory weighted least squares."""
    input:
        maneuvers=maneuver_files("npz"),
        checked=f"{RESULTS}/input.json",
    output:
        point=f"{RESULTS}/{{model}}/point_estimate.npz",
        classic=f"{RESULTS}/{{model}}/classic.csv",
    params:
        campaign_dir=CAMPAIGN_DIR,
        config=config,
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/{{model}}/point_estimate.log",
    script:
        "../scripts/point_estimate.py"
