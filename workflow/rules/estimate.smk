rule classic:
    """The paper's method: hold-averaged error after each rotation per unit rotation (once per campaign)."""
    input:
        maneuvers=maneuver_files("npz"),
    output:
        f"{RESULTS}/classic.csv",
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/classic.log",
    benchmark:
        f"{LOGS}/classic.benchmark.tsv",
    script:
        "../scripts/classic.py"


rule point_estimate:
    """The full-trajectory weighted least squares of one model, started from the classic estimate
    (computed in the job: it takes a tenth of a second, and waiting for the classic rule's job put
    it on the critical path). Ahead of classic when both wait for a core."""
    priority: 1
    input:
        maneuvers=maneuver_files("npz"),
        checked=f"{RESULTS}/input.json",
        plugins=PLUGINS,
    output:
        f"{RESULTS}/{{model}}/point_estimate.npz",
    params:
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
