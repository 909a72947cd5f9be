#!/usr/bin/env bash
# Install envconv with its test extras into ./.venv (created if missing), building the native
# core, then lint (ruff check, ruff format --check) and run the tests; tests/test_architecture.py
# checks the import cycles and layer boundaries of docs/architecture.md.
# Usage: ./run-tests.sh [pytest args...]   (e.g. ENVCONV_TEST_WORKERS=0 ./run-tests.sh -x -k ibl)
set -euo pipefail
cd "$(dirname "$0")"
venv="${ENVCONV_VENV:-.venv}"
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
# The build requirements live in the venv, so that the build folder (build/) is reused and a
# rebuild after editing src/core/ compiles only what changed.
"$venv/bin/python" -m pip install --quiet scikit-build-core nanobind cmake ninja
"$venv/bin/python" -m pip install --quiet --no-build-isolation -e '.[test]'
"$venv/bin/ruff" check envconv tests benchmarks examples
"$venv/bin/ruff" format --check envconv tests benchmarks examples
# One test process per core (pytest-xdist; ENVCONV_TEST_WORKERS overrides, 0 runs in this process):
# on 2 cores the suite takes about two thirds of its serial time.
exec "$venv/bin/python" -m pytest -n "${ENVCONV_TEST_WORKERS:-auto}" "$@"
