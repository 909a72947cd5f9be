"""The fused resampling kernel.

For every output pixel the kernel takes S×S stratified sub-samples at ((i + (sx + 0.5)/S),
(j + (sy + 0.5)/S)) output pixels, scales them to level-0 image points, maps each to a direction
through the output layout (continued into guard rings), rotates it into the source frame, maps it
to a source image point and reads the source through the reconstruction filter. Samples are
weighted by the output layout's solid-angle density, so a pixel is the solid-angle mean of the
environment over the part of it that holds directions. Alpha is the fraction of sub-samples in
the valid region.

Geometry arrives as (geo, cell_face, cell_turns, face_cell); see :mod:`envconv.kernels.cells`.
Tiles are in :mod:`envconv.kernels.tiles`, the auto sub-sample rule in
:mod:`envconv.kernels.footprint`, the rip-map in :mod:`envconv.kernels.ripmap`.
"""

import math

import numpy as np

from .._jit import jit_inline, jit_parallel, prange
from .cells import GEO_FAMILY, cell_local
from .footprint import (
    AUTO_EDGE_SAMPLES,
    auto_count,
    centre_source_y,
    edge_y_part,
    level_span,
    pixel_footprint,
    rip_level,
)
from .geometry import density, is_disk
from .mapping import output_sample as _output_sample
from .mapping import source_point
from .ripmap import level_tap, rip_offset, rows_filled
from .scratch import scratch
from .taps import accumulate_sample
from .tiles import (
    MIN_SUBTILE,
    MIN_TILES_PER_CELL,
    TILE,
    lagrange3,
    map_tile,
    tile_face,
    tile_in_empty_cell,
)

__all__ = ["resample_rows"]


@jit_inline
def _exact_pixel(
    src, sgeo, s_cell_face, s_cell_turns, s_face_cell,
    dgeo, d_cell_face, d_cell_turns, dfam,
    i, j, scale_x, scale_y, nx, ny, filt, rot, fill, acc, tmp, rip, level,
):  # fmt: skip
    """Accumulate output pixel (i, j) mapping its nx × ny sub-samples exactly.

    With ``level`` ≥ 1 (a lat-long source) the taps read that level of the rip-map ``rip``.
    Returns (wsum, nvalid): the summed weights and the number of sub-samples in the valid region.
    """
    s_width = sgeo[3] * sgeo[1]
    start = rip_offset(s_width, level)
    level_width = s_width >> level
    x_scale = 1.0 / (1 << level)
    wsum = 0.0
    nvalid = 0
    for sy in range(ny):
        py = (j + (sy + 0.5) / ny) * scale_y
        for sx in range(nx):
            px = (i + (sx + 0.5) / nx) * scale_x
            face, a, b, readable, valid = _output_sample(
                dgeo, d_cell_face, d_cell_turns, px, py, fill
            )
            if not readable:
                continue
            if valid:
                nvalid += 1
            w = density(dfam, face, a, b)
            spx, spy, scell = source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot)
            if level > 0:
                level_tap(rip, start, level_width, spx * x_scale, spy, w, acc)
            else:
                accumulate_sample(
                    src, sgeo, s_cell_face, s_cell_turns, s_face_cell, scell, spx, spy, filt, w,
                    acc, tmp,
                )  # fmt: skip
            wsum += w
    return wsum, nvalid


# The most sub-samples per pixel edge a tile may take (samples=64 is the API's limit).
MAX_ROW_SAMPLES = 64


@jit_parallel
def resample_rows(
    src, rip, rip_levels, rip_rows, sgeo, s_cell_face, s_cell_turns, s_face_cell,
    dgeo, d_cell_face, d_cell_turns,
    scale_x, scale_y, samples, filt, rot, fill, out, alpha, weights,
):  # fmt: skip
    """Fill ``out`` (H, W, C float32) and ``alpha`` (H, W float32); see the module docstring.

    Pass a (1, 1) ``alpha`` when the coverage is not wanted: a 4096 cross then needs 50 MB less.

    ``weights`` (H, W float64) receives each pixel's sum of sub-sample weights (the solid-angle
    density of its readable sub-samples), from which the mip chain averages blocks of pixels
    with exactly the weights used here; pass a (1, 1) array to skip it.

    ``rip`` holds ``rip_levels`` levels of a lat-long source's rip-map
    (:func:`envconv.kernels.ripmap.build_rips`), filled in the ``rip_rows`` rows next to each
    pole; a pixel or tile whose sub-samples could reach any other row reads level 0 instead.
    Pass ``rip_levels = 0`` (and any array of src's type) when there is none. Levels are used only with adaptive sampling (samples ≤ 0)
    and the bilinear filter. Work is split into bands of TILE output rows, one band per
    parallel task, so the working set is bounded by a few rows whatever the image size.
    """
    height, width, nch = out.shape
    dfam = dgeo[GEO_FAMILY]
    sfam = sgeo[GEO_FAMILY]
    adaptive = samples <= 0
    n_bands = (height + TILE - 1) // TILE
    # Source cells are directly readable rectangles unless the source is a disk layout.
    s_n, s_g, s_aspect, s_cols = sgeo[1], sgeo[2], sgeo[3], sgeo[4]
    s_cw = s_aspect * s_n + 2 * s_g
    s_ch = s_n + 2 * s_g
    fast_taps = filt == 1 and not is_disk(sfam)
    if not (adaptive and fast_taps):
        rip_levels = 0
    s_width = s_aspect * s_n
    s_height = src.shape[0]
    # Tiles small enough against an output cell (level-0 pixels) for the checks to hold.
    d_n, d_aspect = dgeo[1], dgeo[3]
    may_tile = (
        (TILE // 2) * scale_x * MIN_TILES_PER_CELL <= d_aspect * d_n
        and (TILE // 2) * scale_y * MIN_TILES_PER_CELL <= d_n
        and samples <= MAX_ROW_SAMPLES
    )
    largest_tile = TILE // 2
    if TILE * scale_x * MIN_TILES_PER_CELL <= d_aspect * d_n and (
        TILE * scale_y * MIN_TILES_PER_CELL <= d_n
    ):
        largest_tile = TILE
    # A tile that fails its checks is split into quarters, down to MIN_SUBTILE (4 at S = 1, where
    # mapping a 2 × 2 block's grid costs more than its 4 samples), and only blocks that fail at
    # that size map every sub-sample exactly: near a pole or along a seam that is a thin strip.
    min_subtile = 4 if samples == 1 else MIN_SUBTILE
    keep_weights = weights.shape[0] == height and weights.shape[1] == width
    keep_alpha = alpha.shape[0] == height and alpha.shape[1] == width
    for band in prange(n_bands):
        acc = scratch(nch, np.float64)
        tmp = scratch(3 * nch, np.float64)
        for c in range(3 * nch):
            tmp[c] = 0.0
        grid = scratch((3, 3, 3), np.float64)
        rows = scratch((TILE * MAX_ROW_SAMPLES, 9), np.float64)
        stack = scratch((16, 3), np.int64)
        for tile_i0 in range(0, width, TILE):
            stack[0, 0] = tile_i0
            stack[0, 1] = band * TILE
            stack[0, 2] = TILE
            depth = 1
            while depth > 0:
                depth -= 1
                i0 = stack[depth, 0]
                j0 = stack[depth, 1]
                size = stack[depth, 2]
                if i0 >= width or j0 >= height:
                    continue
                i1 = min(i0 + size, width)
                j1 = min(j0 + size, height)
                x0 = i0 * scale_x
                y0 = j0 * scale_y
                x1 = i1 * scale_x
                y1 = j1 * scale_y
                if not fill and tile_in_empty_cell(dgeo, d_cell_face, d_cell_turns, x0, y0, x1, y1):
                    for j in range(j0, j1):
                        for i in range(i0, i1):
                            out[j, i, :] = 0.0
                            if keep_alpha:
                                alpha[j, i] = 0.0
                            if keep_weights:
                                weights[j, i] = 0.0
                    continue
                face = -1
                cell = -1
                if may_tile and size <= largest_tile:
                    face, cell = tile_face(dgeo, d_cell_face, d_cell_turns, x0, y0, x1, y1)
                c00 = -1
                if face >= 0:
                    a00, b00 = cell_local(dgeo, d_cell_turns, cell, x0, y0)
                    a10, b10 = cell_local(dgeo, d_cell_turns, cell, x1, y0)
                    a01, b01 = cell_local(dgeo, d_cell_turns, cell, x0, y1)
                    da_x = a10 - a00
                    db_x = b10 - b00
                    da_y = a01 - a00
                    db_y = b01 - b00
                    c00 = map_tile(
                    sgeo, s_face_cell, s_cell_turns, dfam, face, rot,
                    a00, b00, da_x, db_x, da_y, db_y, grid,
                )  # fmt: skip
                tiled = c00 >= 0
                if not tiled and may_tile and size > min_subtile:
                    half = size // 2
                    for q in range(4):
                        stack[depth, 0] = i0 + half * (q % 2)
                        stack[depth, 1] = j0 + half * (q // 2)
                        stack[depth, 2] = half
                        depth += 1
                    continue
                if not tiled:
                    for j in range(j0, j1):
                        for i in range(i0, i1):
                            for c in range(nch):
                                acc[c] = 0.0
                            nx = samples
                            ny = samples
                            level = 0
                            if adaptive:
                                span_x, span_y, x_of_x, x_of_y = pixel_footprint(
                                sgeo, s_face_cell, s_cell_turns, dgeo, d_cell_face,
                                d_cell_turns, dfam, i, j, scale_x, scale_y, rot, fill,
                            )  # fmt: skip
                                if rip_levels > 0 and x_of_x >= 0.0:
                                    level = rip_level(x_of_x + x_of_y, rip_levels)
                                    if level > 0 and not rows_filled(
                                        centre_source_y(
                                            sgeo, s_face_cell, s_cell_turns, dgeo, d_cell_face,
                                            d_cell_turns, dfam, i, j, scale_x, scale_y, rot, fill,
                                        ),
                                        edge_y_part(span_x, x_of_x) + edge_y_part(span_y, x_of_y),
                                        rip_rows, s_height,
                                    ):  # fmt: skip
                                        level = 0
                                nx = auto_count(level_span(span_x, x_of_x, level))
                                ny = auto_count(level_span(span_y, x_of_y, level))
                                # A pixel not wholly in one cell's valid region (a rim, a cell
                                # edge) needs enough sub-samples for its coverage (alpha).
                                whole, _ = tile_face(
                                dgeo, d_cell_face, d_cell_turns,
                                i * scale_x, j * scale_y, (i + 1) * scale_x, (j + 1) * scale_y,
                            )  # fmt: skip
                                if whole < 0:
                                    nx = max(nx, AUTO_EDGE_SAMPLES)
                                    ny = max(ny, AUTO_EDGE_SAMPLES)
                            wsum, nvalid = _exact_pixel(
                            src, sgeo, s_cell_face, s_cell_turns, s_face_cell,
                            dgeo, d_cell_face, d_cell_turns, dfam,
                            i, j, scale_x, scale_y, nx, ny, filt, rot, fill, acc, tmp,
                            rip, level,
                        )  # fmt: skip
                            _store(out, alpha, j, i, acc, wsum, nvalid / (nx * ny))
                            if keep_weights:
                                weights[j, i] = wsum
                    continue
                bx0 = (c00 % s_cols) * s_cw
                by0 = (c00 // s_cols) * s_ch
                bx1 = bx0 + s_cw - 1
                by1 = by0 + s_ch - 1
                inv_tw = 1.0 / (i1 - i0)
                inv_th = 1.0 / (j1 - j0)
                nx = samples
                ny = samples
                level = 0
                if adaptive:
                    if rip_levels > 0:
                        x_extent = math.inf
                        for k in range(3):
                            x_extent = min(
                                x_extent,
                                abs(grid[k, 2, 0] - grid[k, 0, 0]) * inv_tw
                                + abs(grid[2, k, 0] - grid[0, k, 0]) * inv_th,
                            )
                        level = rip_level(x_extent, rip_levels)
                        if level > 0:
                            y_lo = math.inf
                            y_hi = -math.inf
                            for k in range(3):
                                for m in range(3):
                                    y_lo = min(y_lo, grid[k, m, 1])
                                    y_hi = max(y_hi, grid[k, m, 1])
                            if not rows_filled(0.5 * (y_lo + y_hi), y_hi - y_lo, rip_rows, s_height):
                                level = 0
                    shrink = 1.0 / (1 << level)
                    edge_x = 0.0
                    edge_y = 0.0
                    for k in range(3):
                        edge_x = max(
                            edge_x,
                            math.hypot(
                                (grid[k, 2, 0] - grid[k, 0, 0]) * shrink,
                                grid[k, 2, 1] - grid[k, 0, 1],
                            ),
                        )
                        edge_y = max(
                            edge_y,
                            math.hypot(
                                (grid[2, k, 0] - grid[0, k, 0]) * shrink,
                                grid[2, k, 1] - grid[0, k, 1],
                            ),
                        )
                    nx = auto_count(edge_x * inv_tw)
                    ny = auto_count(edge_y * inv_th)
                # Taps read level 0 (src) or a rip-map level, at x_scale · x + x_offset.
                image = src
                x_scale = 1.0
                x_offset = 0.0
                level_start = 0
                level_width = s_width
                if level > 0:
                    image = rip
                    x_scale = 1.0 / (1 << level)
                    level_start = rip_offset(s_width, level)
                    level_width = s_width >> level
                    x_offset = float(level_start)
                    bx0 = level_start
                    bx1 = level_start + level_width - 1
                inv_nx = 1.0 / nx
                inv_ny = 1.0 / ny
                rgb = fast_taps and nch == 3
                # Each row of sub-samples (j, sy) has source x, source y and weight as
                # quadratics in fx, q0 + fx (c1 + fx c2): 9 numbers per row, shared by the
                # tile's pixels along it.
                for r in range((j1 - j0) * ny):
                    fy = (r // ny + (r % ny + 0.5) * inv_ny) * inv_th
                    for k in range(3):
                        q0 = lagrange3(grid[0, 0, k], grid[1, 0, k], grid[2, 0, k], fy)
                        q1 = lagrange3(grid[0, 1, k], grid[1, 1, k], grid[2, 1, k], fy)
                        q2 = lagrange3(grid[0, 2, k], grid[1, 2, k], grid[2, 2, k], fy)
                        rows[r, 3 * k] = q0
                        rows[r, 3 * k + 1] = -3.0 * q0 + 4.0 * q1 - q2
                        rows[r, 3 * k + 2] = 2.0 * q0 - 4.0 * q1 + 2.0 * q2
                for j in range(j0, j1):
                    for i in range(i0, i1):
                        for c in range(nch):
                            acc[c] = 0.0
                        # Three channels (the common case) accumulate in registers.
                        acc_r = 0.0
                        acc_g = 0.0
                        acc_b = 0.0
                        wsum = 0.0
                        for sy in range(ny):
                            r = (j - j0) * ny + sy
                            q0x = rows[r, 0]
                            c1x = rows[r, 1]
                            c2x = rows[r, 2]
                            q0y = rows[r, 3]
                            c1y = rows[r, 4]
                            c2y = rows[r, 5]
                            q0w = rows[r, 6]
                            c1w = rows[r, 7]
                            c2w = rows[r, 8]
                            for sx in range(nx):
                                fx = (i - i0 + (sx + 0.5) * inv_nx) * inv_tw
                                spx = q0x + fx * (c1x + fx * c2x)
                                spy = q0y + fx * (c1y + fx * c2y)
                                w = q0w + fx * (c1w + fx * c2w)
                                wsum += w
                                tx = spx * x_scale + x_offset - 0.5
                                ty = spy - 0.5
                                ix = int(np.floor(tx))
                                iy = int(np.floor(ty))
                                if fast_taps and ix >= bx0 and iy >= by0 and ix < bx1 and iy < by1:
                                    tx -= ix
                                    ty -= iy
                                    k00 = w * (1.0 - tx) * (1.0 - ty)
                                    k10 = w * tx * (1.0 - ty)
                                    k01 = w * (1.0 - tx) * ty
                                    k11 = w * tx * ty
                                    if rgb:
                                        acc_r += (
                                        k00 * image[iy, ix, 0] + k10 * image[iy, ix + 1, 0]
                                        + k01 * image[iy + 1, ix, 0] + k11 * image[iy + 1, ix + 1, 0]
                                    )  # fmt: skip
                                        acc_g += (
                                        k00 * image[iy, ix, 1] + k10 * image[iy, ix + 1, 1]
                                        + k01 * image[iy + 1, ix, 1] + k11 * image[iy + 1, ix + 1, 1]
                                    )  # fmt: skip
                                        acc_b += (
                                        k00 * image[iy, ix, 2] + k10 * image[iy, ix + 1, 2]
                                        + k01 * image[iy + 1, ix, 2] + k11 * image[iy + 1, ix + 1, 2]
                                    )  # fmt: skip
                                        continue
                                    for c in range(nch):
                                        acc[c] += (
                                            k00 * image[iy, ix, c]
                                            + k10 * image[iy, ix + 1, c]
                                            + k01 * image[iy + 1, ix, c]
                                            + k11 * image[iy + 1, ix + 1, c]
                                        )
                                elif level > 0:
                                    level_tap(
                                        rip, level_start, level_width, spx * x_scale, spy, w, acc
                                    )
                                else:
                                    accumulate_sample(
                                    src, sgeo, s_cell_face, s_cell_turns, s_face_cell, c00,
                                    spx, spy, filt, w, acc, tmp,
                                )  # fmt: skip
                        if rgb:
                            acc[0] += acc_r
                            acc[1] += acc_g
                            acc[2] += acc_b
                        _store(out, alpha, j, i, acc, wsum, 1.0)
                        if keep_weights:
                            weights[j, i] = wsum


@jit_inline
def _store(out, alpha, j, i, acc, wsum, coverage):
    """Write the normalised accumulator and the coverage of output pixel (i, j); the coverage
    only where ``alpha`` has that pixel (a (1, 1) stand-in skips it)."""
    nch = out.shape[2]
    if wsum > 0.0:
        inv = 1.0 / wsum
        for c in range(nch):
            out[j, i, c] = acc[c] * inv
    else:
        for c in range(nch):
            out[j, i, c] = 0.0
    if j < alpha.shape[0] and i < alpha.shape[1]:
        alpha[j, i] = coverage
