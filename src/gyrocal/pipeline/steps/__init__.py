"""The workflow's steps as functions of paths: what the thin Snakemake scripts call.

One module per step, each with a ``run`` that reads the files it is given, calls the physics
and statistics modules and writes its outputs whole or not at all (`gyrocal.io.outputs`); each
takes only the config sections it uses, so a change elsewhere in the config does not rerun it.
A rule's job runs one step, or a step with those that need nothing else and no setting of their
own (preprocess: validate, preprocess, classic; posterior: posterior, calibrate; report:
compare, report), since a job's start-up outweighed their work. Every job is a fresh Python
process, so each module imports only what its step uses: arviz, emcee and matplotlib cost a
second or more to import, and most steps need none of them (`common` holds what every step
shares).
"""

REFUSED = "gyrocal: the campaign was refused:"
"""How a step's message about bad input begins, in its log and on the console. Here, not in
`common`, because the workflow reads it when it builds its DAG and `common` imports the steps'
numerics."""

__all__ = [
    "REFUSED", "calibrate", "classic", "common", "compare_models", "diagnostics", "fleet", "joint", "plan",
    "point_estimate", "posterior", "preprocess", "report", "validate"
]
