"""Interpolated tiles of the resampling kernel: map a tile's 3 × 3 grid, check it, and tell
whether a block of output pixels lies in one cell.

Image points are level-0 pixels; geometry arrives as in :mod:`envconv.kernels.cells`.
"""

import numpy as np

from .._jit import jit_inline
from .cells import locate, point_valid
from .geometry import density
from .mapping import source_point

__all__ = [
    "TILE", "MIN_SUBTILE", "INTERP_TOLERANCE", "WEIGHT_TOLERANCE", "MIN_TILES_PER_CELL",
    "tile_in_empty_cell", "tile_face", "lagrange3", "map_tile",
]  # fmt: skip


@jit_inline
def tile_in_empty_cell(dgeo, d_cell_face, d_cell_turns, x0, y0, x1, y1):
    """True when the level-0 box [x0, x1) × [y0, y1) lies in one cell that holds no face."""
    face, a, b, cell = locate(dgeo, d_cell_face, d_cell_turns, x0, y0)
    if face >= 0:
        return False
    face2, a2, b2, cell2 = locate(
        dgeo, d_cell_face, d_cell_turns, np.nextafter(x1, x0), np.nextafter(y1, y0)
    )
    return cell2 == cell


@jit_inline
def tile_face(dgeo, d_cell_face, d_cell_turns, x0, y0, x1, y1):
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
def lagrange3(g0, g1, g2, f):
    """Quadratic through (0, g0), (0.5, g1), (1, g2), at f."""
    return (
        g0 * (2.0 * f * f - 3.0 * f + 1.0) + g1 * (4.0 * f - 4.0 * f * f) + g2 * (2.0 * f * f - f)
    )


@jit_inline
def map_tile(
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
            px, py, cell = source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot)
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
        px, py, cell = source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot)
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
            interpolated = lagrange3(
                lagrange3(grid[0, 0, k], grid[0, 1, k], grid[0, 2, k], fx),
                lagrange3(grid[1, 0, k], grid[1, 1, k], grid[1, 2, k], fx),
                lagrange3(grid[2, 0, k], grid[2, 1, k], grid[2, 2, k], fx),
                fy,
            )
            if not abs(interpolated - value) <= tolerance:
                return -1
    return cell0
