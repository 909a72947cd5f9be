#!/usr/bin/env bash
# Install envconv with its test extras into ./.venv (created if missing), lint, run the tests.
# Usage: ./run-tests.sh [pytest args...]
set -euo pipefail
cd "$(dirname "$0")"
venv="${ENVCONV_VENV:-.venv}"
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet -e '.[test]'
"$venv/bin/ruff" check envconv tests benchmarks examples
exec "$venv/bin/python" -m pytest "$@"
