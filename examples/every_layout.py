"""Convert one lat-long environment into every layout envconv writes, and report on each.

Usage: python examples/every_layout.py [INPUT] [OUTDIR]

For every layout it writes OUTDIR/<stem>-<layout>.exr (float, scene-linear; cube-faces and
paraboloid-split write one file per face) and an 8-bit sRGB preview of each file in OUTDIR/preview/, then
reads the EXR back, converts it to a lat-long of the input's size and prints:

- the mean radiance over the sphere (solid-angle weighted) of the layout, against the input's:
  the default (area) filter neither gains nor loses energy, so a layout whose mean moves by more
  than 0.5 % is an error (exit status 1);
- the PSNR of the round trip input → layout → lat-long against the input, in dB (relative
  to the input's peak), as a check that nothing moved or mirrored.

A view (fisheye, perspective, with their default fields of view) sees part of the sphere: its
mean is over what it sees, against the input's over the same part (the round trip's alpha),
and its round trip is compared where it sees all of a pixel.
"""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np

import envconv
from envconv.layouts import LAYOUTS
from envconv.layouts.geometry import pixel_solid_angles


def mean_radiance(envmap: envconv.EnvMap) -> np.ndarray:
    """Solid-angle weighted mean of the colour channels over the layout's valid region (per sr)."""
    weights = pixel_solid_angles(envmap.layout, envmap.size, envmap.guard)
    colour = envmap.pixels[:, :, :3].astype(np.float64)
    return (colour * weights[:, :, None]).sum(axis=(0, 1)) / weights.sum()


def psnr(test: np.ndarray, reference: np.ndarray) -> float:
    """Peak signal-to-noise ratio (dB) of ``test`` against ``reference``, peak = reference max."""
    error = np.mean((test.astype(np.float64) - reference) ** 2)
    peak = float(np.max(reference))
    return math.inf if error == 0 else 10.0 * math.log10(peak * peak / error)


def main(argv: list[str]) -> int:
    source_path = argv[1] if len(argv) > 1 else "examples/data/park-latlong-512.exr"
    outdir = argv[2] if len(argv) > 2 else "examples/out"
    os.makedirs(os.path.join(outdir, "preview"), exist_ok=True)
    stem = os.path.basename(source_path).split("-")[0].split(".")[0]

    source = envconv.read(source_path)
    if source.layout.name != "latlong":
        source = envconv.convert(source, "latlong")
    reference = source.pixels[:, :, :3].astype(np.float64)
    source_mean = mean_radiance(source)
    print(f"{source_path}: {source.layout.name} {source.width}x{source.height}, "
          f"mean radiance {np.round(source_mean, 4).tolist()}")  # fmt: skip
    print(f"{'layout':<17} {'size':>11} {'seconds':>8} {'mean radiance (R, G, B)':>30} "
          f"{'round trip':>11}")  # fmt: skip
    off = []
    for name in LAYOUTS:
        disk = name in ("sphere", "angular", "paraboloid", "paraboloid-split")
        start = time.perf_counter()
        out = envconv.convert(source, name, alpha=disk)
        path = os.path.join(outdir, f"{stem}-{name}.exr")
        if name in ("cube-faces", "paraboloid-split"):
            path = os.path.join(outdir, f"{stem}-{name}-{{face}}.exr")
        envconv.write(out, path)
        preview = os.path.join(outdir, "preview", os.path.basename(path).replace(".exr", ".png"))
        clipped: list[str] = []  # an 8-bit preview clips highlights; that is expected here
        envconv.write(out, preview, output_colorspace="sRGB", bit_depth="uint8", warnings=clipped)
        seconds = time.perf_counter() - start

        back = envconv.read(path, layout=name if "{face}" in path else None)
        mean = mean_radiance(back)
        partial = back.layout.partial
        round_trip = envconv.convert(back, "latlong", size=source.size, alpha=partial)
        seen = round_trip.pixels[:, :, 3] if partial else np.ones(reference.shape[:2])
        quality = psnr(round_trip.pixels[:, :, :3][seen == 1], reference[seen == 1])
        expected = source_mean
        note = "  (faces overlap: mean over 3π√2 sr)" if name == "tennisball" else ""
        if partial:  # the input's mean over what the view sees
            weights = pixel_solid_angles(source.layout, source.size) * seen
            expected = (reference * weights[:, :, None]).sum(axis=(0, 1)) / weights.sum()
            note = f"  (a view: the input there {np.round(expected, 4).tolist()})"
        print(f"{name:<17} {f'{out.width}x{out.height}':>11} {seconds:8.2f} "
              f"{str(np.round(mean, 4).tolist()):>30} {quality:8.1f} dB{note}")  # fmt: skip
        if name != "tennisball" and np.max(np.abs(mean / expected - 1)) > 0.005:
            off.append(name)
    if off:
        # The area filter (the default) keeps every texel's energy: this is a defect to report.
        print(
            f"error: {', '.join(off)} moved the mean radiance by more than 0.5 %", file=sys.stderr
        )
        return 1
    print(f"wrote {outdir}/")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
