rule classic:
    """The paper's method: hold-averaged error after each rotation per unit rotation (once per campaign)."""
    input:
        preprocessed=PREPROCESSED,
    output:
        f"{RESULTS}/classic.csv",
    params:
        maneuvers=maneuver_files("npz"),
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
