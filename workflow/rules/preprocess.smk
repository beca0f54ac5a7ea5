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
    """Every maneuver of a campaign: slice, propagate every channel set nominally, error angles of
    eq. 4; a table and figure each. One job per campaign, since a maneuver takes a fraction of
    a second and a job's start-up more."""
    input:
        unpack(campaign_input),
        checked=f"{RESULTS}/input.json",
    output:
        report(
            directory(PREPROCESSED),
            patterns=["{maneuver}.png"],
            caption="../report/preprocess.rst",
            category="Maneuvers",
            subcategory="{maneuver}",
        ),
    params:
        campaign_dir=campaign_dir,
    threads: 2  # its figures are drawn in parallel; it runs alone, before the models split the cores
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/preprocess.log",
    benchmark:
        f"{LOGS}/preprocess.benchmark.tsv",
    script:
        "../scripts/preprocess.py"
