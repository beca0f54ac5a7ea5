#!/usr/bin/env bash
# Install gyrocal with its test dependencies and run the default test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
python -m pip install --quiet -e ".[test]"
python -m pytest "$@"
