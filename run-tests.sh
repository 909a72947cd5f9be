#!/usr/bin/env bash
# Install envconv with its test extras into ./.venv (created if missing), building the native
# core, then lint (ruff check, ruff format --check) and run the tests; tests/test_architecture.py
# checks the import cycles and layer boundaries of docs/architecture.md.
# Usage: ./run-tests.sh [pytest args...]   (e.g. ENVCONV_TEST_WORKERS=0 ./run-tests.sh -x -k ibl)
# Progress goes to stderr, one line per stage (scripts/install.sh).
set -euo pipefail
cd "$(dirname "$0")"
venv="${ENVCONV_VENV:-.venv}"
. scripts/install.sh
envconv_install '.[test]'
_stage "ruff check and ruff format --check"
"$venv/bin/ruff" check envconv tests benchmarks examples
"$venv/bin/ruff" format --check envconv tests benchmarks examples
# The tests start the command line several hundred times: its modules are compiled once here,
# so that each start reads bytecode even where PYTHONDONTWRITEBYTECODE keeps Python from
# caching it (about 80 ms a start on this project's machines).
"$venv/bin/python" -m compileall -q envconv
# One test process per core (pytest-xdist; ENVCONV_TEST_WORKERS overrides, 0 runs in this process):
# on 2 cores the suite takes about two thirds of its serial time.
_stage "pytest (one test process per core)"
exec "$venv/bin/python" -m pytest -n "${ENVCONV_TEST_WORKERS:-auto}" "$@"
