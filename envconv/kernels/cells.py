"""Cell bookkeeping inside kernels: image point ↔ (face, a, b).

A layout's geometry is passed to kernels as an int64 vector ``geo`` plus three int32 tables
(see :meth:`envconv.layouts.base.Layout.kernel_tables`):

    geo = [family, N, G, aspect, columns, rows]

Image points are in level-0 pixels: x right, y down, pixel (i, j) spans [i, i+1) × [j, j+1).
"""

import math

from .._jit import jit, jit_inline
from .geometry import is_disk

__all__ = [
    "locate",
    "face_to_image",
    "cell_local",
    "nearest_cell",
    "point_valid",
    "point_readable",
]

GEO_FAMILY, GEO_N, GEO_GUARD, GEO_ASPECT, GEO_COLUMNS, GEO_ROWS = 0, 1, 2, 3, 4, 5
ON_EDGE = 1e-9  # tolerance of the validity test (rim directions land at R² = 1 + O(1e-16))


@jit_inline
def cell_local(geo, cell_turns, cell, px, py):
    """Local (a, b) of image point (px, py) in the frame of ``cell``, continued past it."""
    n, g, aspect, cols = geo[GEO_N], geo[GEO_GUARD], geo[GEO_ASPECT], geo[GEO_COLUMNS]
    cw = aspect * n + 2 * g
    ch = n + 2 * g
    col = cell % cols
    row = cell // cols
    a = 2.0 * (px - col * cw - g) / (aspect * n) - 1.0
    b = 2.0 * (py - row * ch - g) / n - 1.0
    if cell_turns[cell] == 2:
        return -a, -b
    return a, b


@jit_inline
def locate(geo, cell_face, cell_turns, px, py):
    """(face, a, b, cell) of image point (px, py); face is -1 in an empty cell."""
    n, g, aspect = geo[GEO_N], geo[GEO_GUARD], geo[GEO_ASPECT]
    cols, rows = geo[GEO_COLUMNS], geo[GEO_ROWS]
    col = min(max(int(math.floor(px / (aspect * n + 2 * g))), 0), cols - 1)
    row = min(max(int(math.floor(py / (n + 2 * g))), 0), rows - 1)
    cell = row * cols + col
    a, b = cell_local(geo, cell_turns, cell, px, py)
    return cell_face[cell], a, b, cell


@jit_inline
def face_to_image(geo, face_cell, cell_turns, face, a, b):
    """Image point (px, py) and cell of local point (a, b) of ``face``."""
    n, g, aspect, cols = geo[GEO_N], geo[GEO_GUARD], geo[GEO_ASPECT], geo[GEO_COLUMNS]
    cell = face_cell[face]
    if cell_turns[cell] == 2:
        a, b = -a, -b
    col = cell % cols
    row = cell // cols
    px = col * (aspect * n + 2 * g) + g + 0.5 * (a + 1.0) * aspect * n
    py = row * (n + 2 * g) + g + 0.5 * (b + 1.0) * n
    return px, py, cell


@jit_inline
def point_valid(geo, face, a, b):
    """True when (a, b) of ``face`` lies in the layout's valid region (not guard)."""
    if face < 0:
        return False
    if is_disk(geo[GEO_FAMILY]):
        return a * a + b * b <= 1.0 + ON_EDGE
    return abs(a) <= 1.0 + ON_EDGE and abs(b) <= 1.0 + ON_EDGE


@jit_inline
def point_readable(geo, face, a, b):
    """True when (a, b) holds data: the valid region or the guard ring around it."""
    if face < 0:
        return False
    if is_disk(geo[GEO_FAMILY]):
        r = 1.0 + 2.0 * geo[GEO_GUARD] / geo[GEO_N]
        return a * a + b * b <= r * r + ON_EDGE
    return True


@jit
def nearest_cell(geo, cell_face, px, py):
    """Cell whose valid region is nearest to (px, py) in pixels; ties go to the lower face."""
    n, g, aspect = geo[GEO_N], geo[GEO_GUARD], geo[GEO_ASPECT]
    cols, rows = geo[GEO_COLUMNS], geo[GEO_ROWS]
    cw = aspect * n + 2 * g
    ch = n + 2 * g
    disk = is_disk(geo[GEO_FAMILY])
    best_cell, best_face, best_d = -1, 1 << 30, 1e300
    for cell in range(cols * rows):
        face = cell_face[cell]
        if face < 0:
            continue
        x0 = (cell % cols) * cw + g
        y0 = (cell // cols) * ch + g
        if disk:
            dx = px - (x0 + 0.5 * n)
            dy = py - (y0 + 0.5 * n)
            d = max(math.sqrt(dx * dx + dy * dy) - 0.5 * n, 0.0)
        else:
            dx = max(x0 - px, 0.0, px - (x0 + aspect * n))
            dy = max(y0 - py, 0.0, py - (y0 + n))
            d = math.sqrt(dx * dx + dy * dy)
        if d < best_d or (d == best_d and face < best_face):
            best_cell, best_face, best_d = cell, face, d
    return best_cell
