#!/usr/bin/env bash
# Install envconv into ./.venv (created if missing), building the native core, and convert the
# bundled lat-long example into every layout envconv writes, with a report, into examples/out/.
# Usage: ./run-example.sh [INPUT.exr]
set -euo pipefail
cd "$(dirname "$0")"
venv="${ENVCONV_VENV:-.venv}"
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet scikit-build-core nanobind cmake ninja
"$venv/bin/python" -m pip install --quiet --no-build-isolation -e .
exec "$venv/bin/python" examples/every_layout.py "${1:-examples/data/park-latlong-512.exr}" examples/out
