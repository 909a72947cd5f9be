#!/usr/bin/env bash
# One read, two outputs: each resampled once, from the source (docs/shell.md).
# Usage: examples/shell.sh [OUTDIR]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-build/shell}"
mkdir -p "$out"

envconv read "$here/data/park-latlong-512.exr" \
    resample --to cube-vcross --size 128 write "$out/park_cross.exr" \
    resample --to paraboloid --size 64 --alpha --guard 2 write "$out/park_para.exr"

# The same first output with the one-line shorthand; the pixels are identical.
envconv convert "$here/data/park-latlong-512.exr" "$out/park_cross_convert.exr" \
    --to cube-vcross --size 128
