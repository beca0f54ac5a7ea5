#!/usr/bin/env bash
# Install gyrocal with its test dependencies (and Chromium for the browser test), lint, run the tests.
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
python -m pip install --quiet -e ".[test]"
python -m ruff check .
python -m snakemake --lint >/dev/null
python -m pytest "$@"
