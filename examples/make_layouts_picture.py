"""Make docs/img/every-layout.png: the Venice example in every layout, converted by envconv.

Usage: python examples/make_layouts_picture.py [OUTPUT]

Each layout is converted at a size that makes its image about ROW_HEIGHT pixels tall, with
alpha for the disk layouts (shown over a grey checkerboard, so the valid region shows), then
encoded to 8-bit sRGB and laid out in rows with OpenImageIO.
"""

from __future__ import annotations

import os
import sys

import numpy as np
import OpenImageIO as oiio

import envconv

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.join(HERE, "data", "venice-latlong-512.exr")
ROW_HEIGHT = 180
GAP = 12
ROWS = [
    ["latlong", "tennisball"],
    ["cube-vcross", "cube-hcross", "cube-exr"],
    ["cube-hstrip"],
    ["sphere", "angular", "paraboloid", "octahedral", "equal-area"],
    ["eac", "fisheye", "perspective"],
]


def _srgb(linear: np.ndarray) -> np.ndarray:
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def _tile(source: envconv.EnvMap, name: str) -> np.ndarray:
    layout = envconv.layouts.get_layout(name)
    rows_of_n = layout.image_size(1)[1]
    size = max(1, ROW_HEIGHT // rows_of_n)
    out = envconv.convert(source, name, size=size, alpha=True)
    rgb = out.pixels[..., :3] * 0.6  # about -0.7 stop, so the sky is not clipped to white
    alpha = out.pixels[..., out.alpha_index]
    height, width = alpha.shape
    yy, xx = np.mgrid[0:height, 0:width]
    checker = np.where(((yy // 8) + (xx // 8)) % 2 == 0, 0.05, 0.1)[..., None]
    empty = np.full_like(rgb, 0.02)  # empty cross cells: near black
    background = np.where(out.pixels[..., :1] * 0 + (alpha[..., None] > 0), checker, empty)
    composite = rgb * alpha[..., None] + background * (1.0 - alpha[..., None])
    return _srgb(composite)


def main(argv: list[str]) -> int:
    output = (
        argv[1] if len(argv) > 1 else os.path.join(HERE, "..", "docs", "img", "every-layout.png")
    )
    source = envconv.read(SOURCE)
    rows = [[_tile(source, name) for name in names] for names in ROWS]
    widths = [sum(t.shape[1] for t in row) + GAP * (len(row) - 1) for row in rows]
    heights = [max(t.shape[0] for t in row) for row in rows]
    canvas_w = max(widths) + 2 * GAP
    canvas_h = sum(heights) + GAP * (len(rows) + 1)
    canvas = np.ones((canvas_h, canvas_w, 3), np.float32)
    y = GAP
    for row, width, height in zip(rows, widths, heights, strict=True):
        x = (canvas_w - width) // 2
        for tile in row:
            canvas[y : y + tile.shape[0], x : x + tile.shape[1]] = tile
            x += tile.shape[1] + GAP
        y += height + GAP
    image = oiio.ImageBuf(oiio.ImageSpec(canvas_w, canvas_h, 3, oiio.UINT8))
    image.set_pixels(oiio.ROI(), canvas)
    if not image.write(output):
        raise SystemExit(f"cannot write {output}: {image.geterror()}")
    print(f"wrote {output} ({canvas_w}x{canvas_h})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
