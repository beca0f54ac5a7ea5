#!/usr/bin/env bash
# The tests, by tier (README, "Tests"):
#   bash tests/run.sh            the fast tier, what CI runs: lint, the layers contract, the docs site,
#                                unit tests and short-chain integration tests (a few minutes on 2 cores)
#   bash tests/run.sh --full     every test but the studies and Slurm: the statistical integration tests
#                                with the default sampler settings too
#   bash tests/run.sh -m slow    the long statistical studies
# Any other arguments go to pytest. Installs gyrocal with its workflow, test and docs extras (and Chromium for the
# browser test) first.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v chromium >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ]; then
        apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
    else
        echo "tests/run.sh: Chromium is missing and this user cannot apt-get it; the browser test will skip" >&2
    fi
fi
# One BLAS thread per process, as Snakemake gives each one-thread rule: numpy's and scipy's OpenBLAS
# otherwise spin two threads each on the posterior's small products (4x the CPU on a 2-core machine).
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
python -m pip install --quiet -e ".[workflow,test,docs]"
python -m ruff check .
lint-imports --no-logo --no-cache
# The workflow linted, under its config and under each small config of .test/ (snakemake-workflows' layout),
# each of those dry-run, and the docs site built: side by side, one process each on both cores (they
# are independent); the first that fails ends the tier with its own message, and stops the others.
lint() { python -m snakemake --lint "$@" >/dev/null 2>&1 || python -m snakemake --lint "$@"; }
jobs=()
lint & jobs+=($!)
for config in .test/config/*.yaml; do
    (lint --configfile "$config" && python -m snakemake -n -q --configfile "$config" -d "$(mktemp -d)" >/dev/null) &
    jobs+=($!)
done
NO_MKDOCS_2_WARNING=1 mkdocs build --strict --quiet --site-dir "$(mktemp -d)" & jobs+=($!)
for _ in "${jobs[@]}"; do
    wait -n || { status=$?; kill "${jobs[@]}" 2>/dev/null || true; exit "$status"; }
done
if [ "${1:-}" = "--full" ]; then
    shift
    set -- -m "not slow and not slurm" "$@"
fi
# Two workers, one a core; a file's tests stay on one worker, so its module fixtures run once. The files in
# the order tests/conftest.py gives them (the longest first), not xdist's (the most tests first).
python -m pytest -n 2 --dist loadfile --no-loadscope-reorder "$@"
