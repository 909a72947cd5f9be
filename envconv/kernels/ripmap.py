"""Horizontal rip-map of a lat-long source, for reading its polar rows cheaply.

Near a lat-long's poles a row's length shrinks as cos(latitude), so one output pixel there can
span tens of texels in x and one or two in y. Taking enough sub-samples to read every one of
them costs up to 32 × more than elsewhere. Instead the kernel reads a level that is already
averaged along x, and takes sub-samples by the footprint measured in that level's texels.

Level k (k ≥ 1) averages 2^k texels along x and none along y::

    level 0  | a | b | c | d | e | f | g | h |      W texels per row
    level 1  |  (a+b)/2  |  (c+d)/2  |  ...  |      W / 2
    level 2  |      (a+b+c+d)/4      |  ...  |      W / 4

Texel i of level k is the mean of level-0 texels i·2^k … (i+1)·2^k − 1 of the same row, so its
centre sits at level-0 x = (i + 0.5)·2^k: the pixel-centre rule holds at every level, and a
level-0 image point x is point x / 2^k of level k. Rows keep their latitude, so the wrap in x
and the continuation over a pole (row −1 is row 0 half a turn away) are the same at every
level. Box averages preserve each row's sum, so no energy is gained or lost.

Levels 1 … K are packed side by side in one (H, W − W_K, C) float32 array; level k starts at
column W − 2·W_k, where W_k = W / 2^k. K stops where W_k would be odd (the pole continuation
shifts by W_k / 2) or smaller than RIP_MIN_WIDTH.
"""

import math

import numpy as np

from .._jit import jit_inline, jit_parallel, prange

__all__ = ["rip_level_count", "rip_offset", "build_rips", "level_tap", "rows_filled",
           "RIP_MAX_LEVELS", "RIP_ROW_MARGIN"]  # fmt: skip

RIP_MAX_LEVELS = 8
RIP_MIN_WIDTH = 8


def rip_level_count(width: int) -> int:
    """Number of levels K a lat-long ``width`` texels wide can carry (see module docstring)."""
    levels = 0
    while (
        levels < RIP_MAX_LEVELS
        and width % (2 ** (levels + 2)) == 0
        and width >> (levels + 1) >= RIP_MIN_WIDTH
    ):
        levels += 1
    return levels


@jit_inline
def rip_offset(width, level):
    """First column of ``level`` (≥ 1) in the packed array of a source ``width`` texels wide."""
    return width - 2 * (width >> level)


@jit_parallel
def _fill_rips(src, levels, rows, out):
    height, width, nch = src.shape
    filled = min(2 * rows, height)
    for r in prange(filled):
        j = np.int64(r)  # a parfor index may be unsigned: keep the row arithmetic signed
        if j >= rows:
            j += height - filled
        w1 = width >> 1
        for i in range(w1):
            for c in range(nch):
                out[j, i, c] = 0.5 * (np.float64(src[j, 2 * i, c]) + src[j, 2 * i + 1, c])
        prev = 0
        for k in range(2, levels + 1):
            start = rip_offset(width, k)
            for i in range(width >> k):
                for c in range(nch):
                    out[j, start + i, c] = 0.5 * (
                        np.float64(out[j, prev + 2 * i, c]) + out[j, prev + 2 * i + 1, c]
                    )
            prev = start


def build_rips(src: np.ndarray, rows: int | None = None, out: np.ndarray | None = None):
    """(packed levels, K) for a lat-long ``src`` (H, W, C) float32; K = 0 when none fit.

    Only the ``rows`` rows next to each pole are filled (all rows when None): the array is
    allocated whole but never touched elsewhere, so the memory of the other rows is not used
    (the kernel never reads them; see ``rip_rows`` in :mod:`envconv.kernels.resample`).
    ``out``, when given, is the (H, W − W / 2^K, C) float32 array to fill.
    """
    height, width, nch = src.shape
    levels = rip_level_count(width)
    if levels == 0:
        return np.zeros((1, 1, nch), np.float32), 0
    if out is None:
        out = np.empty((height, width - (width >> levels), nch), np.float32)
    _fill_rips(src, levels, height if rows is None else int(rows), out)
    return out, levels


# Rows beyond a footprint's reach that a rip-map read may touch: the bilinear tap's second row,
# the continuation over a pole, and the slack of interpolated tiles.
RIP_ROW_MARGIN = 3.0


@jit_inline
def rows_filled(y, extent, rows, height):
    """Whether sub-samples within ``extent`` source rows of row position ``y`` stay in the
    rip-map rows that :func:`build_rips` filled: the ``rows`` next to each pole."""
    if 2 * rows >= height:
        return True
    reach = extent + RIP_ROW_MARGIN
    return y + reach <= rows or y - reach >= height - rows


@jit_inline
def level_tap(rip, start, level_width, x, y, w, acc):
    """Add ``w`` × the bilinear read of one level at its point (x, y) to ``acc``.

    (x, y) is in the level's texels (x = level-0 x / 2^k). Taps past the ends of a row wrap;
    taps past the first or last row continue over the pole: row −1 is row 0, and row H is row
    H − 1, shifted by half a turn.
    """
    height = rip.shape[0]
    nch = rip.shape[2]
    fx = x - 0.5
    fy = y - 0.5
    x0 = int(math.floor(fx))
    y0 = int(math.floor(fy))
    tx = fx - x0
    ty = fy - y0
    for k in range(4):
        ix = x0 + (k & 1)
        iy = y0 + (k >> 1)
        kw = w * (tx if k & 1 else 1.0 - tx) * (ty if k >> 1 else 1.0 - ty)
        if iy < 0:
            iy = -1 - iy
            ix += level_width // 2
        elif iy >= height:
            iy = 2 * height - 1 - iy
            ix += level_width // 2
        iy = min(max(iy, 0), height - 1)
        ix = ix % level_width
        for c in range(nch):
            acc[c] += kw * rip[iy, start + ix, c]
