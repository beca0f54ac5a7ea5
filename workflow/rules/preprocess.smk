rule preprocess:
    """Read and check the campaign (format and physics: bad input stops the run here), record rows,
    checksums and what was left out (input.json); then every maneuver: slice, propagate every
    channel set nominally, error angles of eq. 4, a table and figure each; then the paper's method
    over them (classic.csv, its sd from the noise knowledge). Everything a campaign gives with no model, in one job:
    each part takes a fraction of a second, and a job's start-up more (the steps stay apart in
    gyrocal.pipeline.steps: validate, preprocess, classic)."""
    input:
        unpack(campaign_input),
    output:
        checked=PATHS.input_json,
        classic=PATHS.classic,
        preprocessed=report(
            directory(PATHS.preprocess),
            patterns=["{maneuver}.png"],
            caption="../report/preprocess.rst",
            category="Maneuvers",
            subcategory="{maneuver}",
        ),
    params:
        campaign_dir=campaign_dir,
        block_s=config["sampler"]["block_s"],  # validation refuses a maneuver too short for the posterior's blocks
        noise=_canonical(config["noise"]),  # the classic values' sd and the pilot fit's weights, where campaign.yaml states no noise
        reference_interval_s=config["reference_interval_s"],  # star-tracker samples kept every this many seconds, or "auto"
    threads: 2  # its figures are drawn in parallel; it runs alone, before the models split the cores
    conda:
        "../envs/gyrocal.yaml"
    log:
        f"{LOGS}/preprocess.log",
    benchmark:
        f"{LOGS}/preprocess.benchmark.tsv",
    script:
        "../scripts/preprocess.py"
