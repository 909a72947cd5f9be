#!/usr/bin/env bash
# Convert every lat-long in data/ to a cube cross and a guarded paraboloid (docs/batch.md).
# Usage: examples/batch.sh [OUTDIR]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-build/batch}"

envconv batch "$here/data" --out "$out/{stem}_{layout}.exr" -j 2 --report "$out/report.json" \
    resample --to cube-vcross --size 64 \
    resample --to paraboloid --size 32 --alpha --guard 1

# Run again in update mode: nothing is newer than its outputs, so everything is skipped.
envconv batch "$here/data" --out "$out/{stem}_{layout}.exr" --update \
    resample --to cube-vcross --size 64 \
    resample --to paraboloid --size 32 --alpha --guard 1
