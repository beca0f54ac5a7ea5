"""The workflow's steps as functions of paths: what the thin Snakemake scripts call.

One module per rule, each with a ``run`` that reads the files its rule declares, calls
the physics and statistics modules and writes its outputs whole or not at all
(`gyrocal.outputs`); each takes only the config sections it uses, so a change elsewhere
in the config does not rerun it. Every job is a fresh Python process, so each module
imports only what its step uses: arviz, emcee and matplotlib cost a second or more to
import, and most steps need none of them (`common` holds what every step shares).
"""

REFUSED = "gyrocal: the campaign was refused:"
"""How a step's message about bad input begins, in its log and on the console. Here, not in
`common`, because the workflow reads it when it builds its DAG and `common` imports the steps'
numerics."""
