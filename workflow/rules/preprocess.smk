rule validate:
    """Read and check the campaign; record rows, checksums and what was skipped."""
    input:
        unpack(campaign_input),
    output:
        f"{RESULTS}/input.json",
    params:
        campaign_dir=campaign_dir,
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/validate.log",
    benchmark:
        f"{LOGS}/validate.benchmark.tsv",
    script:
        "../scripts/validate.py"


rule preprocess:
    """One maneuver: slice, propagate every channel set nominally, error angles of eq. 4."""
    input:
        unpack(campaign_input),
        checked=f"{RESULTS}/input.json",
    output:
        data=f"{RESULTS}/preprocess/{{maneuver}}.npz",
        table=f"{RESULTS}/preprocess/{{maneuver}}.csv",
        figure=report(
            f"{RESULTS}/preprocess/{{maneuver}}.png",
            caption="../report/preprocess.rst",
            category="Maneuvers",
            subcategory="{maneuver}",
        ),
    params:
        campaign_dir=campaign_dir,
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/preprocess/{{maneuver}}.log",
    benchmark:
        f"{LOGS}/preprocess/{{maneuver}}.benchmark.tsv",
    script:
        "../scripts/preprocess.py"
