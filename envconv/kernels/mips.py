"""Kernel of the mip chain: exact block reduction.

A pixel of :func:`envconv.kernels.resample.resample_rows` is the density-weighted mean of its
S×S readable sub-samples, and the kernel also returns that weight sum Σw for every pixel. A
texel of a coarser level whose footprint is a whole block of finer texels is then exactly
``Σ_c w_c v_c / Σ_c w_c`` over the block (:func:`reduce_blocks`): the same sub-samples, the
same weights, the same cells, as a direct computation with S·bx sub-samples per edge (which
may interpolate weights over different tiles: to the kernel's WEIGHT_TOLERANCE). Alpha
(coverage) is the plain mean of the block's coverages, since every texel of a block has the
same image area.
"""

import numpy as np

from .._jit import jit_parallel, prange
from .resample import _store
from .scratch import scratch

__all__ = ["reduce_blocks"]


@jit_parallel
def reduce_blocks(src, wsrc, asrc, bx, by, out, wout, aout):
    """Weighted means of bx × by blocks: out (h, w, C), weight sums wout, mean coverage aout."""
    height, width, nch = out.shape
    inv_area = 1.0 / (bx * by)
    for j in prange(height):
        acc = scratch(nch, np.float64)
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
