#!/bin/sh
# The default run's rules and what each needs (docs/images/rulegraph.png), from the repository's root:
#   sh docs/images/rulegraph.sh          (needs Graphviz: apt-get install graphviz)
set -e
snakemake --rulegraph --quiet all 2>/dev/null | dot -Tpng -Gdpi=110 -o docs/images/rulegraph.png
