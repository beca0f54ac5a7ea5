"""gyrocal: in-flight gyro calibration from single-axis maneuvers (see README.md)."""

from snakemake.utils import min_version, validate

min_version("8.0")


configfile: f"{workflow.basedir}/config/config.yaml"


validate(config, "workflow/schemas/config.schema.yaml")


include: "workflow/rules/common.smk"
include: "workflow/rules/simulate.smk"
include: "workflow/rules/preprocess.smk"
include: "workflow/rules/estimate.smk"
include: "workflow/rules/posterior.smk"
include: "workflow/rules/diagnostics.smk"
include: "workflow/rules/report.smk"
include: "workflow/rules/fleet.smk"


rule all:
    input:
        all_outputs(),
    default_target: True


onsuccess:
    cancel_rescheduling_timers()


onerror:
    refusals = refusal_messages()
    if refusals:
        print("\n".join(refusals), file=sys.stderr)
