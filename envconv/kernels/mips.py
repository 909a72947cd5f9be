"""Kernels of the mip chain: per-pixel sample weights and exact block reduction.

A pixel of :func:`envconv.kernels.resample.resample_rows` is the density-weighted mean of its
S×S readable sub-samples. :func:`pixel_weights` returns that weight sum Σw for every pixel, from
the same sub-sample positions. A texel of a coarser level whose footprint is a whole block of
finer texels is then exactly ``Σ_c w_c v_c / Σ_c w_c`` over the block (:func:`reduce_blocks`):
the same sub-samples, the same weights, the same cells, as a direct computation with S·bx
sub-samples per edge. Alpha (coverage) is the plain mean of the block's coverages, since every
texel of a block has the same image area.
"""

import numpy as np
from numba import prange

from .._jit import jit_parallel
from .cells import GEO_FAMILY
from .geometry import density
from .mapping import output_sample as _output_sample
from .resample import _store

__all__ = ["pixel_weights", "reduce_blocks"]


@jit_parallel
def pixel_weights(dgeo, d_cell_face, d_cell_turns, scale_x, scale_y, samples, fill, wsum):
    """Σ density (sr per unit (a, b) area) of each pixel's readable S×S sub-samples, (H, W)."""
    height, width = wsum.shape
    dfam = dgeo[GEO_FAMILY]
    inv_s = 1.0 / samples
    for j in prange(height):
        for i in range(width):
            total = 0.0
            for sy in range(samples):
                py = (j + (sy + 0.5) * inv_s) * scale_y
                for sx in range(samples):
                    px = (i + (sx + 0.5) * inv_s) * scale_x
                    face, a, b, readable, valid = _output_sample(
                        dgeo, d_cell_face, d_cell_turns, px, py, fill
                    )
                    if readable:
                        total += density(dfam, face, a, b)
            wsum[j, i] = total


@jit_parallel
def reduce_blocks(src, wsrc, asrc, bx, by, out, wout, aout):
    """Weighted means of bx × by blocks: out (h, w, C), weight sums wout, mean coverage aout."""
    height, width, nch = out.shape
    inv_area = 1.0 / (bx * by)
    for j in prange(height):
        acc = np.zeros(nch, np.float64)
        for i in range(width):
            for c in range(nch):
                acc[c] = 0.0
            wt = 0.0
            at = 0.0
            for y in range(j * by, (j + 1) * by):
                for x in range(i * bx, (i + 1) * bx):
                    at += asrc[y, x]
                    w = wsrc[y, x]
                    if w > 0.0:
                        wt += w
                        for c in range(nch):
                            acc[c] += w * src[y, x, c]
            _store(out, aout, j, i, acc, wt, at * inv_area)
            wout[j, i] = wt
