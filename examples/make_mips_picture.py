"""Make docs/img/paraboloid-mips.png: every level of a MIP-mapped packed paraboloid.

Runs, through envconv's own CLI,

    envconv convert venice-latlong-512.exr out.exr --to paraboloid --size 254 --alpha --guard 1 --mips

then reads every level back from the MIP-mapped EXR and tiles them: level 0 (512 × 256) on the
left, levels 1, 2, … stacked in the right-hand column at their own sizes. Colour is exposed and
sRGB-encoded for display; pixels with alpha 0 (the guard ring and the corners) are drawn over a
grey checkerboard at half strength, so the valid region and the guard ring both show.

    python examples/make_mips_picture.py
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, ROOT)

from envconv import io  # noqa: E402

SOURCE = os.path.join(HERE, "data", "venice-latlong-512.exr")
TARGET = os.path.join(ROOT, "docs", "img", "paraboloid-mips.png")


def _display(rgba: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Tone-mapped sRGB of an RGBA level over a checkerboard where alpha < 1."""
    rgb = np.clip(rgba[..., :3] * exposure, 0.0, None)
    rgb = rgb / (1.0 + rgb)  # Reinhard, keeps highlights in range
    srgb = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * rgb ** (1 / 2.4) - 0.055)
    h, w = rgba.shape[:2]
    y, x = np.mgrid[0:h, 0:w]
    checker = np.where(((x // 4) + (y // 4)) % 2, 0.55, 0.45)[..., None]
    alpha = np.clip(rgba[..., 3:4], 0.0, 1.0)
    shown = 0.5 + 0.5 * alpha  # invalid pixels drawn at half strength over the checkerboard
    return srgb * shown + checker * (1 - shown)


def main() -> None:
    exe = os.path.join(os.path.dirname(sys.executable), "envconv")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.exr")
        cmd = [exe, "convert", SOURCE, out, "--to", "paraboloid", "--size", "254", "--alpha",
               "--guard", "1", "--mips"]  # fmt: skip
        subprocess.run(cmd, check=True, capture_output=True)
        sizes = io.mip_levels(out)
        levels = [io.read_image(out, k)[0] for k in range(len(sizes))]
    w0, h0 = sizes[0]
    column = sum(level.shape[0] + 2 for level in levels[1:])
    canvas = np.ones((max(h0, column), w0 + w0 // 2 + 4, 3), np.float32)
    canvas[:h0, :w0] = _display(levels[0])
    y = 0
    for level in levels[1:]:
        h, w = level.shape[:2]
        canvas[y : y + h, w0 + 4 : w0 + 4 + w] = _display(level)
        y += h + 2
    os.makedirs(os.path.dirname(TARGET), exist_ok=True)
    _write_png(canvas, TARGET)
    print(f"{TARGET}: {len(sizes)} levels, level 0 {w0}x{h0}")


def _write_png(pixels: np.ndarray, path: str) -> None:
    """Write display-referred pixels (already sRGB-encoded) as an 8-bit PNG."""
    import OpenImageIO as oiio  # only this example script, not the library, writes raw PNG

    codes = np.clip(np.round(pixels * 255.0), 0, 255).astype(np.uint8)
    height, width = codes.shape[:2]
    out = oiio.ImageOutput.create(path)
    spec = oiio.ImageSpec(width, height, 3, oiio.UINT8)
    spec.attribute("oiio:ColorSpace", "sRGB")
    if not (out.open(path, spec) and out.write_image(codes) and out.close()):
        raise SystemExit(f"cannot write {path}: {out.geterror()}")


if __name__ == "__main__":
    main()
