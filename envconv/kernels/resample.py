"""The fused resampling kernel and its per-pixel helpers.

For every output pixel the kernel takes S×S stratified sub-samples at ((i + (sx + 0.5)/S),
(j + (sy + 0.5)/S)) output pixels, scales them to level-0 image points, maps each to a direction
through the output layout (continued into guard rings), rotates it into the source frame, maps it
to a source image point and reads the source through the reconstruction filter. Samples are
weighted by the output layout's solid-angle density, so a pixel is the solid-angle mean of the
environment over the part of it that holds directions. Alpha is the fraction of sub-samples in
the valid region.

Geometry arrives as (geo, cell_face, cell_turns, face_cell); see :mod:`envconv.kernels.cells`.
"""

import math

import numpy as np
from numba import prange

from .._jit import jit_inline, jit_parallel
from .cells import (
    GEO_FAMILY,
    cell_local,
    face_to_image,
    locate,
    point_valid,
)
from .geometry import density, dir_to_face, face_to_dir, is_disk
from .mapping import output_sample as _output_sample
from .ripmap import level_tap, rip_offset
from .taps import accumulate_sample

__all__ = ["resample_rows"]


@jit_inline
def _source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot):
    """Source image point and cell of output point (a, b) of ``face``, after rotation."""
    x, y, z = face_to_dir(dfam, face, a, b)
    xs = rot[0, 0] * x + rot[0, 1] * y + rot[0, 2] * z
    ys = rot[1, 0] * x + rot[1, 1] * y + rot[1, 2] * z
    zs = rot[2, 0] * x + rot[2, 1] * y + rot[2, 2] * z
    sface, sa, sb = dir_to_face(sgeo[GEO_FAMILY], xs, ys, zs)
    return face_to_image(sgeo, s_face_cell, s_cell_turns, sface, sa, sb)


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
            spx, spy, scell = _source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot)
            if level > 0:
                level_tap(rip, start, level_width, spx * x_scale, spy, w, acc)
            else:
                accumulate_sample(
                    src, sgeo, s_cell_face, s_cell_turns, s_face_cell, scell, spx, spy, filt, w,
                    acc, tmp,
                )  # fmt: skip
            wsum += w
    return wsum, nvalid


@jit_inline
def _auto_count(footprint):
    """Sub-samples along an edge that spans ``footprint`` source pixels (see AUTO_SPACING)."""
    n = int(math.ceil(footprint / AUTO_SPACING - AUTO_SLACK))
    return min(max(n, 1), AUTO_MAX_SAMPLES)


@jit_inline
def _one_sided_span(
    sgeo, s_face_cell, s_cell_turns, dgeo, d_cell_face, d_cell_turns, dfam, rot, fill,
    face, px, py, step_x, step_y, sx0, sy0, cell0,
):  # fmt: skip
    """Source pixels per output pixel along (step_x, step_y), by a forward or backward
    difference of a hundredth of a pixel, whichever stays in one output face and one source
    cell and moves less (the other may jump across a seam); -1 when neither does.

    Returns (span, |x component of the span|).
    """
    delta = 0.01
    best = -1.0
    best_x = -1.0
    for side in (1.0, -1.0):
        qx = px + side * delta * step_x
        qy = py + side * delta * step_y
        qface, qa, qb, readable, valid = _output_sample(
            dgeo, d_cell_face, d_cell_turns, qx, qy, fill
        )
        if not readable or qface != face:
            continue
        sx, sy, cell = _source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, qa, qb, rot)
        if cell != cell0:
            continue
        span = math.hypot(sx - sx0, sy - sy0) / delta
        if best < 0.0 or span < best:
            best = span
            best_x = abs(sx - sx0) / delta
    return best, best_x


@jit_inline
def _pixel_footprint(
    sgeo, s_face_cell, s_cell_turns, dgeo, d_cell_face, d_cell_turns, dfam,
    i, j, scale_x, scale_y, rot, fill,
):  # fmt: skip
    """Source pixels spanned by the x and y edges of output pixel (i, j), at its centre.

    From the Jacobian of the map output point → source point, by differences over a hundredth
    of a pixel: anisotropic, so a mirror ball's rim (radially squeezed) or a lat-long's polar
    rows (stretched in x) get their sub-samples along the axis that needs them. Each difference
    is taken on the side that does not cross a seam (a lat-long's wrap, a face edge, an output
    cell edge); where both sides do, the isotropic √(Ω_out / Ω_in) of the pixel solid angles is
    used instead. Returns (span_x, span_y, x_of_span_x, x_of_span_y): the last two are the
    source-x components of the two edges (for choosing a rip-map level), -1 where only the
    isotropic estimate exists; all -1 when the centre holds no direction (outside a disk).
    """
    px = (i + 0.5) * scale_x
    py = (j + 0.5) * scale_y
    face, a, b, readable, valid = _output_sample(dgeo, d_cell_face, d_cell_turns, px, py, fill)
    if not readable:
        return -1.0, -1.0, -1.0, -1.0
    sx0, sy0, cell0 = _source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot)
    span_x, x_of_x = _one_sided_span(
        sgeo, s_face_cell, s_cell_turns, dgeo, d_cell_face, d_cell_turns, dfam, rot, fill,
        face, px, py, scale_x, 0.0, sx0, sy0, cell0,
    )  # fmt: skip
    span_y, x_of_y = _one_sided_span(
        sgeo, s_face_cell, s_cell_turns, dgeo, d_cell_face, d_cell_turns, dfam, rot, fill,
        face, px, py, 0.0, scale_y, sx0, sy0, cell0,
    )  # fmt: skip
    if span_x >= 0.0 and span_y >= 0.0:
        return span_x, span_y, x_of_x, x_of_y
    # A seam between the points: the ratio of the two pixels' solid angles (density × area).
    d_area = (2.0 * scale_x / (dgeo[3] * dgeo[1])) * (2.0 * scale_y / dgeo[1])
    s_area = (2.0 / (sgeo[3] * sgeo[1])) * (2.0 / sgeo[1])
    x, y, z = face_to_dir(dfam, face, a, b)
    xs = rot[0, 0] * x + rot[0, 1] * y + rot[0, 2] * z
    ys = rot[1, 0] * x + rot[1, 1] * y + rot[1, 2] * z
    zs = rot[2, 0] * x + rot[2, 1] * y + rot[2, 2] * z
    sfam = sgeo[GEO_FAMILY]
    sface, sa, sb = dir_to_face(sfam, xs, ys, zs)
    omega_in = density(sfam, sface, sa, sb) * s_area
    omega_out = density(dfam, face, a, b) * d_area
    if omega_in <= omega_out * 1e-6:  # a degenerate point of the source (angular's rim)
        return 1e3, 1e3, -1.0, -1.0
    ratio = math.sqrt(omega_out / omega_in)
    return ratio, ratio, -1.0, -1.0


@jit_inline
def _tile_in_empty_cell(dgeo, d_cell_face, d_cell_turns, x0, y0, x1, y1):
    """True when the level-0 box [x0, x1) × [y0, y1) lies in one cell that holds no face."""
    face, a, b, cell = locate(dgeo, d_cell_face, d_cell_turns, x0, y0)
    if face >= 0:
        return False
    face2, a2, b2, cell2 = locate(
        dgeo, d_cell_face, d_cell_turns, np.nextafter(x1, x0), np.nextafter(y1, y0)
    )
    return cell2 == cell


@jit_inline
def _tile_face(dgeo, d_cell_face, d_cell_turns, x0, y0, x1, y1):
    """(face, cell) when the level-0 box [x0, x1] × [y0, y1] lies in one cell's valid region.

    The valid region is convex (a rectangle or a disk), so checking the four corners suffices.
    Returns face -1 otherwise.
    """
    face, a, b, cell = locate(dgeo, d_cell_face, d_cell_turns, x0, y0)
    if face < 0 or not point_valid(dgeo, face, a, b):
        return -1, cell
    xe = np.nextafter(x1, x0)
    ye = np.nextafter(y1, y0)
    for k in range(3):
        px = xe if k != 1 else x0
        py = ye if k != 0 else y0
        face2, a2, b2, cell2 = locate(dgeo, d_cell_face, d_cell_turns, px, py)
        if cell2 != cell or not point_valid(dgeo, face, a2, b2):
            return -1, cell
    return face, cell


# Tiles of TILE × TILE output pixels (TILE / 2 when a cell is too small for TILE; see
# MIN_TILES_PER_CELL) map a 3 × 3 grid of points exactly (corners, edge midpoints,
# centre); the source position of every sub-sample inside is interpolated biquadratically from
# them. The map is then checked exactly at the four quarter points (1/4 or 3/4 along each axis),
# where the cubic error of that interpolation is near its largest. If a check is more than
# INTERP_TOLERANCE source pixels off (a seam, a pole, a wrap, strong curvature), or a grid point
# lands in another source cell, the tile is split into four quarters that try again, down to
# MIN_SUBTILE pixels; a block that still fails maps every sub-sample exactly. Tiles are only
# tried when they span at most 1/MIN_TILES_PER_CELL of a cell, so that higher-order terms, which
# the checks could miss, are negligible. At INTERP_TOLERANCE = 0.01 texel, a sub-sample's read
# is off by at most 1% of the difference between neighbouring texels. Weights (the output
# layout's solid-angle density) are interpolated the same way and checked to WEIGHT_TOLERANCE,
# relative: an error that small and that smooth changes a pixel's mean by about 1e-4 of its
# contrast, and no pixel's solid angle (its share of the energy) depends on it.
TILE = 16
MIN_SUBTILE = 2
INTERP_TOLERANCE = 0.01
WEIGHT_TOLERANCE = 1e-3
MIN_TILES_PER_CELL = 8


@jit_inline
def _lagrange3(g0, g1, g2, f):
    """Quadratic through (0, g0), (0.5, g1), (1, g2), at f."""
    return (
        g0 * (2.0 * f * f - 3.0 * f + 1.0) + g1 * (4.0 * f - 4.0 * f * f) + g2 * (2.0 * f * f - f)
    )


@jit_inline
def _map_tile(
    sgeo, s_face_cell, s_cell_turns, dfam, face, rot, a00, b00, da_x, db_x, da_y, db_y, grid,
):  # fmt: skip
    """Map the tile's 3 × 3 grid into ``grid`` (3, 3, 3): source x, source y and the output
    layout's solid-angle density, and check the quarter points.

    Returns the source cell when biquadratic interpolation of the grid is within
    INTERP_TOLERANCE texels of the exact map, and within WEIGHT_TOLERANCE (relative) of the
    exact density, and the whole grid lies in that cell, else -1.
    """
    cell0 = -1
    for r in range(3):
        for c in range(3):
            a = a00 + da_x * (0.5 * c) + da_y * (0.5 * r)
            b = b00 + db_x * (0.5 * c) + db_y * (0.5 * r)
            px, py, cell = _source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot)
            if r == 0 and c == 0:
                cell0 = cell
            elif cell != cell0:
                return -1
            grid[r, c, 0] = px
            grid[r, c, 1] = py
            grid[r, c, 2] = density(dfam, face, a, b)
    for q in range(4):
        fx = 0.25 + 0.5 * (q % 2)
        fy = 0.25 + 0.5 * (q // 2)
        a = a00 + da_x * fx + da_y * fy
        b = b00 + db_x * fx + db_y * fy
        px, py, cell = _source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot)
        if cell != cell0:
            return -1
        for k in range(3):
            if k == 0:
                value = px
                tolerance = INTERP_TOLERANCE
            elif k == 1:
                value = py
                tolerance = INTERP_TOLERANCE
            else:
                value = density(dfam, face, a, b)
                tolerance = WEIGHT_TOLERANCE * value
            interpolated = _lagrange3(
                _lagrange3(grid[0, 0, k], grid[0, 1, k], grid[0, 2, k], fx),
                _lagrange3(grid[1, 0, k], grid[1, 1, k], grid[1, 2, k], fx),
                _lagrange3(grid[2, 0, k], grid[2, 1, k], grid[2, 2, k], fx),
                fy,
            )
            if not abs(interpolated - value) <= tolerance:
                return -1
    return cell0


# samples <= 0 asks for adaptive sub-sampling: each pixel (or tile) takes nx × ny sub-samples
# with nx = ceil(footprint_x / AUTO_SPACING - AUTO_SLACK), where footprint_x is the number of
# source pixels its edge spans there. In a reduction (footprint ≥ 2) sub-samples are then about
# half a texel apart, so every texel under the pixel is read and nothing aliases. Up to a
# footprint of 2 a pixel takes one sample, as sharp as a single-tap converter: one bilinear tap
# reads 2 × 2 texels, so taps 2 texels apart still read every texel, and averaging several taps
# there only blurs (about 1 dB on a same-size round trip, where cube corners reach 1.9).
# Tiles measure the footprint along each axis from their grid, exactly mapped pixels from the
# Jacobian at their centre (both anisotropic: a lat-long's polar rows, a mirror ball's rim). A
# pixel that is not wholly inside one cell's valid region (a disk's rim, a cell edge) takes at
# least AUTO_EDGE_SAMPLES per edge, so that its coverage (alpha) is exact to 1/AUTO_EDGE_SAMPLES².
AUTO_SPACING = 0.5
AUTO_SLACK = 3.0
AUTO_MAX_SAMPLES = 32
AUTO_EDGE_SAMPLES = 8
# The most sub-samples per pixel edge a tile may take (samples=64 is the API's limit).
MAX_ROW_SAMPLES = 64

# With a rip-map (a lat-long source, adaptive sampling, bilinear filter; see
# envconv.kernels.ripmap), a pixel whose footprint spans X level-0 texels along the source's x
# (the x components of its two edges, added) reads level k, the largest with
# 2^k · RIP_MIN_SPAN ≤ X, and counts its sub-samples by the footprint in level-k texels. The
# box of 2^k texels that level averages is then at most 1/RIP_MIN_SPAN of the footprint's width,
# and sub-samples stay about half a level-k texel apart, so nothing aliases. A polar-cap pixel
# spanning 50 texels in x reads level 2 with 22 sub-samples along x rather than 32; over the top
# face of a 512 cube from a 2048 × 1024 lat-long the mean count falls from 6.4 to 3.7. The box and the
# bilinear tent of level k widen the pixel's footprint by about 2^k texels on each side; at
# RIP_MIN_SPAN = 4 that cost 4 × the brute-force error on stripes that converge on a pole
# (tests/test_ripmap.py), at 8 it costs 13%.
RIP_MIN_SPAN = 8.0


@jit_inline
def _rip_level(x_extent, levels):
    """Rip-map level for a footprint ``x_extent`` level-0 texels wide (see RIP_MIN_SPAN)."""
    level = 0
    while level < levels and RIP_MIN_SPAN * (2 << level) <= x_extent:
        level += 1
    return level


@jit_inline
def _level_span(span, x_part, level):
    """Length in level-``level`` texels of an edge ``span`` level-0 texels long whose x
    component is ``x_part`` (levels shrink x by 2^level and keep y)."""
    if level == 0:
        return span
    shrink = 1.0 / (1 << level)
    return math.sqrt(max(span * span - x_part * x_part * (1.0 - shrink * shrink), 0.0))


@jit_parallel
def resample_rows(
    src, rip, rip_levels, sgeo, s_cell_face, s_cell_turns, s_face_cell,
    dgeo, d_cell_face, d_cell_turns,
    scale_x, scale_y, samples, filt, rot, fill, out, alpha, weights,
):  # fmt: skip
    """Fill ``out`` (H, W, C float32) and ``alpha`` (H, W float32); see the module docstring.

    ``weights`` (H, W float64) receives each pixel's sum of sub-sample weights (the solid-angle
    density of its readable sub-samples), from which the mip chain averages blocks of pixels
    with exactly the weights used here; pass a (1, 1) array to skip it.

    ``rip`` holds ``rip_levels`` levels of a lat-long source's rip-map
    (:func:`envconv.kernels.ripmap.build_rips`); pass ``rip_levels = 0`` (and any array of
    src's type) when there is none. Levels are used only with adaptive sampling (samples ≤ 0)
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
    for band in prange(n_bands):
        acc = np.zeros(nch, np.float64)
        tmp = np.zeros(3 * nch, np.float64)
        grid = np.empty((3, 3, 3), np.float64)
        rows = np.empty((TILE * MAX_ROW_SAMPLES, 9), np.float64)
        stack = np.empty((16, 3), np.int64)
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
                if not fill and _tile_in_empty_cell(
                    dgeo, d_cell_face, d_cell_turns, x0, y0, x1, y1
                ):
                    for j in range(j0, j1):
                        for i in range(i0, i1):
                            out[j, i, :] = 0.0
                            alpha[j, i] = 0.0
                            if keep_weights:
                                weights[j, i] = 0.0
                    continue
                face = -1
                cell = -1
                if may_tile and size <= largest_tile:
                    face, cell = _tile_face(dgeo, d_cell_face, d_cell_turns, x0, y0, x1, y1)
                c00 = -1
                if face >= 0:
                    a00, b00 = cell_local(dgeo, d_cell_turns, cell, x0, y0)
                    a10, b10 = cell_local(dgeo, d_cell_turns, cell, x1, y0)
                    a01, b01 = cell_local(dgeo, d_cell_turns, cell, x0, y1)
                    da_x = a10 - a00
                    db_x = b10 - b00
                    da_y = a01 - a00
                    db_y = b01 - b00
                    c00 = _map_tile(
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
                                span_x, span_y, x_of_x, x_of_y = _pixel_footprint(
                                sgeo, s_face_cell, s_cell_turns, dgeo, d_cell_face,
                                d_cell_turns, dfam, i, j, scale_x, scale_y, rot, fill,
                            )  # fmt: skip
                                if rip_levels > 0 and x_of_x >= 0.0:
                                    level = _rip_level(x_of_x + x_of_y, rip_levels)
                                nx = _auto_count(_level_span(span_x, x_of_x, level))
                                ny = _auto_count(_level_span(span_y, x_of_y, level))
                                # A pixel not wholly in one cell's valid region (a rim, a cell
                                # edge) needs enough sub-samples for its coverage (alpha).
                                whole, _ = _tile_face(
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
                        level = _rip_level(x_extent, rip_levels)
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
                    nx = _auto_count(edge_x * inv_tw)
                    ny = _auto_count(edge_y * inv_th)
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
                        q0 = _lagrange3(grid[0, 0, k], grid[1, 0, k], grid[2, 0, k], fy)
                        q1 = _lagrange3(grid[0, 1, k], grid[1, 1, k], grid[2, 1, k], fy)
                        q2 = _lagrange3(grid[0, 2, k], grid[1, 2, k], grid[2, 2, k], fy)
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
    """Write the normalised accumulator and the coverage of output pixel (i, j)."""
    nch = out.shape[2]
    if wsum > 0.0:
        inv = 1.0 / wsum
        for c in range(nch):
            out[j, i, c] = acc[c] * inv
    else:
        for c in range(nch):
            out[j, i, c] = 0.0
    alpha[j, i] = coverage
