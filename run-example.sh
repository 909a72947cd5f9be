#!/usr/bin/env bash
# Install envconv into ./.venv (created if missing), building the native core, and convert the
# bundled lat-long example into every layout envconv writes, with a report, into examples/out/.
# Usage: ./run-example.sh [INPUT.exr]
#        ./run-example.sh --install-only    (install and build, convert nothing)
# Progress goes to stderr, one line per stage (scripts/install.sh).
set -euo pipefail
cd "$(dirname "$0")"
venv="${ENVCONV_VENV:-.venv}"
. scripts/install.sh
envconv_install .
if [ "${1:-}" = "--install-only" ]; then
    exit 0
fi
_stage "converting ${1:-examples/data/park-latlong-512.exr} into every layout (examples/out/)"
exec "$venv/bin/python" examples/every_layout.py "${1:-examples/data/park-latlong-512.exr}" examples/out
