"""Mip chains of environment maps: every level right for its own resolution.

Level k of a W0 × H0 image is ``W_k = max(W0 >> k, 1)`` by ``H_k = max(H0 >> k, 1)`` (rounded
down, as OpenEXR's ROUND_DOWN mode and GPUs do); multi-file layouts apply the rule to each file
(cell), so the cells of every level stay whole texels. A full chain has
``floor(log2(max(w, h))) + 1`` levels and ends at 1 × 1, which is what an OpenEXR MIPMAP_LEVELS
file holds. Every level keeps level 0's uv ↔ direction mapping: the texel (i, j) of level k
covers level-0 pixels ``[i·W0/W_k, (i+1)·W0/W_k) × [j·H0/H_k, (j+1)·H0/H_k)``, and one texture
transform serves every level.

Method
------
Each texel is the solid-angle mean of the environment over the readable part of its footprint,
and its alpha is the fraction of the footprint in the valid region (docs/geometry.md, "Mip
chains"). Level 0 comes from the resampler with S×S sub-samples per pixel. A level whose texel
grid nests in an already computed level j (``W_j % W_k == 0`` and ``H_j % H_k == 0``, always the
case when N + 2G is a power of two) is reduced from level j **exactly**: each texel is the
weighted mean of its block of level-j texels, weighted by their sub-sample weight sums Σw. This
is the same estimator, sample for sample, as resampling level k directly with
``S · W0/W_k`` sub-samples per edge, costs one pass over level j, and never mixes cells (each
sub-sample was already attributed to its own cell). A level that does not nest (odd sizes) is
resampled directly: from the finest computed level that is itself a whole map of the layout
(N and G divisible by 2^j) and at least twice as fine, else from the source with
``S_k = S · W0/W_k`` (capped at 32).

Examples
--------
>>> import numpy as np, envconv
>>> sky = envconv.EnvMap(np.ones((64, 128, 3), np.float32), "latlong")
>>> cube = envconv.convert(sky, "cube-vcross", size=16, mips=True)
>>> [level.shape[:2] for level in cube.levels]
[(64, 48), (32, 24), (16, 12), (8, 6), (4, 3), (2, 1), (1, 1)]
"""

from __future__ import annotations

import logging
import math

import numpy as np

from ..envmap import EnvMap
from ..errors import UsageError
from ..layouts import Layout, get_layout
from ..layouts.geometry import kernel_geometry
from . import kernels

__all__ = [
    "mip_sizes",
    "full_level_count",
    "level_count",
    "build_chain",
]

log = logging.getLogger(__name__)

MAX_LEVEL_SAMPLES = 32


def full_level_count(width: int, height: int) -> int:
    """Levels of a full round-down chain of a ``width`` × ``height`` file: floor(log2 max) + 1."""
    return max(int(width), int(height), 1).bit_length()


def level_count(layout: Layout | str, size: int, guard: int, mips) -> int:
    """Number of levels that ``mips`` asks for (True: full chain; K: at most K; falsy: 1)."""
    layout = get_layout(layout)
    full = full_level_count(*layout.file_size(size, guard))
    if mips is None or mips is False:
        return 1
    if mips is True:
        return full
    try:
        count = int(mips)
    except (TypeError, ValueError):
        raise UsageError(f"mips must be True or a number of levels, got {mips!r}") from None
    if count < 0:
        raise UsageError(f"mips must be a positive number of levels, got {count}")
    return full if count == 0 else min(count, full)


def mip_sizes(
    layout: Layout | str, size: int, guard: int = 0, levels=True
) -> list[tuple[int, int]]:
    """(W_k, H_k) of the in-memory image of each level (the mosaic for multi-file layouts).

    Examples
    --------
    >>> mip_sizes("paraboloid", 254, guard=1)[:3]
    [(512, 256), (256, 128), (128, 64)]
    """
    layout = get_layout(layout)
    count = level_count(layout, size, guard, levels)
    fw, fh = layout.file_size(size, guard)
    mx, my = (layout.columns, layout.rows) if layout.multi_file else (1, 1)
    return [(mx * max(fw >> k, 1), my * max(fh >> k, 1)) for k in range(count)]


def _run_direct(source, sgeo, rot, dgeo_all, fill, shape, scale, samples, filt, coverage=True):
    """Resample one level directly: (pixels (H, W, C), coverage (H, W) or None without
    ``coverage``, weights (H, W))."""
    height, width = shape
    out = np.empty((height, width, source.shape[2]), np.float32)
    coverage = np.empty((height, width), np.float32) if coverage else None
    weights = np.empty((height, width), np.float32)
    source = np.ascontiguousarray(source)
    no_rips = np.zeros((1, 1, source.shape[2]), np.float32)  # mips use one fixed S
    kernels.resample_rows(
        source, no_rips, 0, 0, sgeo, dgeo_all, scale[0], scale[1], samples, filt, rot, fill,
        out, coverage, weights,
    )  # fmt: skip
    return out, coverage, weights


def build_chain(
    source: EnvMap,
    to: Layout | str,
    size: int,
    guard: int,
    fill: bool,
    samples: int,
    filt: int,
    rot: np.ndarray,
    level0: np.ndarray,
    coverage0: np.ndarray,
    weights0: np.ndarray,
    count: int,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Levels 0 … count-1 as (pixels (H_k, W_k, C) float32, coverage (H_k, W_k) float32).

    ``coverage0`` None: no level's coverage is made (every coverage is None), which saves a
    plane per level when no alpha channel is wanted.
    ``level0``, ``coverage0`` and ``weights0`` (each pixel's sum of sub-sample weights) are the
    resampler's output for level 0, made with ``samples`` sub-samples per edge, ``filt`` and
    the output→source rotation ``rot``; see the module docstring for how the other levels are
    made.
    """
    to = get_layout(to)
    sizes = mip_sizes(to, size, guard, count)
    levels = [(level0, coverage0, weights0)]
    for k in range(1, len(sizes)):
        wk, hk = sizes[k]
        nest = [j for j in range(k) if sizes[j][0] % wk == 0 and sizes[j][1] % hk == 0]
        if nest:
            j = nest[-1]
            src, cov, wts = levels[j]
            bx, by = sizes[j][0] // wk, sizes[j][1] // hk
            out = np.empty((hk, wk, src.shape[2]), np.float32)
            cov_k = None if cov is None else np.empty((hk, wk), np.float32)
            wts_k = np.empty((hk, wk), np.float32)
            kernels.reduce_blocks(src, wts, cov, bx, by, out, wts_k, cov_k)
            levels.append((out, cov_k, wts_k))
            continue
        levels.append(
            _fallback_level(source, to, size, guard, fill, samples, filt, rot, sizes, levels, k)
        )
    return [(pixels, coverage) for pixels, coverage, _ in levels]


def _fallback_level(source, to, size, guard, fill, samples, filt, rot, sizes, levels, k):
    """Resample level k directly, from a finer whole-map level if there is one."""
    wk, hk = sizes[k]
    w0, h0 = sizes[0]
    scale = (w0 / wk, h0 / hk)
    dgeo_all = kernel_geometry(to, size, guard)
    cover = levels[0][1] is not None
    if filt == kernels.AREA_FILTER and (guard or fill):
        # A level whose cells are no longer whole texels has no ring to keep apart from its
        # cells' pixels: it is made as the point kernel makes it, from a finer level.
        filt = kernels.FILTER_BILINEAR
    if filt == kernels.AREA_FILTER:
        # The area filter integrates each texel of level k exactly, from the source itself.
        log.debug("mip level %d: %dx%d from the source, exact area", k, wk, hk)
        sgeo = kernel_geometry(source.layout, source.size, source.guard)
        return _run_direct(source.pixels, sgeo, rot, dgeo_all, fill, (hk, wk), scale, 1, filt,
                           cover)  # fmt: skip
    for j in range(k - 1, 0, -1):
        step = 1 << j
        wj, hj = sizes[j]
        whole = size % step == 0 and guard % step == 0 and (wj * step, hj * step) == (w0, h0)
        if whole and wj >= 2 * wk and hj >= 2 * hk:
            finer = EnvMap(levels[j][0], to, guard // step)
            sgeo = kernel_geometry(to, size // step, guard // step)
            s_k = min(max(math.ceil(2 * max(wj / wk, hj / hk)), 1), MAX_LEVEL_SAMPLES)
            log.debug("mip level %d: %dx%d from level %d, S=%d", k, wk, hk, j, s_k)
            return _run_direct(
                finer.pixels, sgeo, np.eye(3), dgeo_all, fill, (hk, wk), scale, s_k, filt, cover
            )
    s_k = min(max(round(samples * math.sqrt(scale[0] * scale[1])), 1), MAX_LEVEL_SAMPLES)
    log.debug("mip level %d: %dx%d from the source, S=%d", k, wk, hk, s_k)
    sgeo = kernel_geometry(source.layout, source.size, source.guard)
    return _run_direct(source.pixels, sgeo, rot, dgeo_all, fill, (hk, wk), scale, s_k, filt,
                       cover)  # fmt: skip
