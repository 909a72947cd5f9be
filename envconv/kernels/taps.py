"""Seam-aware source reads: nearest, bilinear and clamped Catmull-Rom (bicubic) filters.

A tap is a source texel. A tap inside the sample's own (grown) cell, and for disk layouts inside
the readable radius, is read directly. Any other tap is never read as stored: its centre is
mapped with the cell's continued mapping to a direction, and the texel that owns that direction
is read instead. Taps past a cube face's edge thus read the neighbouring face, lat-long taps
wrap and continue over the poles, and taps past a disk read across the rim.
"""

import math

from .._jit import jit, jit_inline
from .cells import (
    GEO_ASPECT,
    GEO_COLUMNS,
    GEO_FAMILY,
    GEO_GUARD,
    GEO_N,
    cell_local,
    face_to_image,
)
from .geometry import dir_to_face, face_to_dir, is_disk

__all__ = ["FILTER_NEAREST", "FILTER_BILINEAR", "FILTER_BICUBIC", "accumulate_sample"]

FILTER_NEAREST = 0
FILTER_BILINEAR = 1
FILTER_BICUBIC = 2


@jit_inline
def _tap_ok(geo, cell, ix, iy):
    """True when texel (ix, iy) lies in ``cell``'s readable region."""
    n, g, aspect, cols = geo[GEO_N], geo[GEO_GUARD], geo[GEO_ASPECT], geo[GEO_COLUMNS]
    cw = aspect * n + 2 * g
    ch = n + 2 * g
    x0 = (cell % cols) * cw
    y0 = (cell // cols) * ch
    if ix < x0 or ix >= x0 + cw or iy < y0 or iy >= y0 + ch:
        return False
    if is_disk(geo[GEO_FAMILY]):
        a = 2.0 * (ix + 0.5 - x0 - g) / n - 1.0
        b = 2.0 * (iy + 0.5 - y0 - g) / n - 1.0
        r = 1.0 + 2.0 * g / n
        return a * a + b * b <= r * r
    return True


@jit
def _remap_tap(geo, cell_face, cell_turns, face_cell, cell, ix, iy):
    """Flat index (iy, ix) of the texel that holds the continued direction of a foreign tap."""
    n, g, aspect, cols = geo[GEO_N], geo[GEO_GUARD], geo[GEO_ASPECT], geo[GEO_COLUMNS]
    family = geo[GEO_FAMILY]
    a, b = cell_local(geo, cell_turns, cell, ix + 0.5, iy + 0.5)
    x, y, z = face_to_dir(family, cell_face[cell], a, b)
    face2, a2, b2 = dir_to_face(family, x, y, z)
    px, py, cell2 = face_to_image(geo, face_cell, cell_turns, face2, a2, b2)
    cw = aspect * n + 2 * g
    ch = n + 2 * g
    x0 = (cell2 % cols) * cw + g
    y0 = (cell2 // cols) * ch + g
    jx = min(max(int(math.floor(px)), x0), x0 + aspect * n - 1)
    jy = min(max(int(math.floor(py)), y0), y0 + n - 1)
    return jx, jy


@jit_inline
def _fetch(src, geo, cell_face, cell_turns, face_cell, cell, ix, iy, fast):
    """Source texel coordinates for tap (ix, iy): itself, or its continued-direction owner."""
    if fast or _tap_ok(geo, cell, ix, iy):
        return ix, iy
    return _remap_tap(geo, cell_face, cell_turns, face_cell, cell, ix, iy)


@jit
def _cubic_weights(t):
    """Catmull-Rom weights for offsets -1, 0, 1, 2 at fraction t."""
    t2 = t * t
    t3 = t2 * t
    w0 = 0.5 * (-t3 + 2.0 * t2 - t)
    w1 = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0)
    w2 = 0.5 * (-3.0 * t3 + 4.0 * t2 + t)
    w3 = 0.5 * (t3 - t2)
    return w0, w1, w2, w3


@jit_inline
def _block_inside(geo, cell, x_lo, y_lo, x_hi, y_hi):
    """True when every texel of [x_lo, x_hi] × [y_lo, y_hi] is directly readable."""
    n, g, aspect, cols = geo[GEO_N], geo[GEO_GUARD], geo[GEO_ASPECT], geo[GEO_COLUMNS]
    cw = aspect * n + 2 * g
    ch = n + 2 * g
    x0 = (cell % cols) * cw
    y0 = (cell // cols) * ch
    if x_lo < x0 or x_hi >= x0 + cw or y_lo < y0 or y_hi >= y0 + ch:
        return False
    if is_disk(geo[GEO_FAMILY]):
        return (
            _tap_ok(geo, cell, x_lo, y_lo)
            and _tap_ok(geo, cell, x_hi, y_lo)
            and _tap_ok(geo, cell, x_lo, y_hi)
            and _tap_ok(geo, cell, x_hi, y_hi)
        )
    return True


@jit_inline
def accumulate_sample(src, geo, cell_face, cell_turns, face_cell, cell, px, py, filt, w, acc, tmp):
    """Add ``w`` × (filtered source at image point (px, py) of ``cell``) to ``acc``.

    ``tmp`` is scratch of length 3 × channels (bicubic clamping bounds).
    """
    nch = src.shape[2]
    if filt == FILTER_NEAREST:
        ix = int(math.floor(px))
        iy = int(math.floor(py))
        jx, jy = _fetch(src, geo, cell_face, cell_turns, face_cell, cell, ix, iy, False)
        for c in range(nch):
            acc[c] += w * src[jy, jx, c]
        return
    fx = px - 0.5
    fy = py - 0.5
    x0 = int(math.floor(fx))
    y0 = int(math.floor(fy))
    tx = fx - x0
    ty = fy - y0
    if filt == FILTER_BILINEAR:
        fast = _block_inside(geo, cell, x0, y0, x0 + 1, y0 + 1)
        ax, ay = _fetch(src, geo, cell_face, cell_turns, face_cell, cell, x0, y0, fast)
        bx, by = _fetch(src, geo, cell_face, cell_turns, face_cell, cell, x0 + 1, y0, fast)
        cx, cy = _fetch(src, geo, cell_face, cell_turns, face_cell, cell, x0, y0 + 1, fast)
        dx, dy = _fetch(src, geo, cell_face, cell_turns, face_cell, cell, x0 + 1, y0 + 1, fast)
        w00 = w * (1.0 - tx) * (1.0 - ty)
        w10 = w * tx * (1.0 - ty)
        w01 = w * (1.0 - tx) * ty
        w11 = w * tx * ty
        for c in range(nch):
            acc[c] += (
                w00 * src[ay, ax, c]
                + w10 * src[by, bx, c]
                + w01 * src[cy, cx, c]
                + w11 * src[dy, dx, c]
            )
        return
    # Catmull-Rom over 4×4 taps, clamped to the range of the central 2×2 taps so that it
    # cannot ring past its neighbours (no new negatives next to an HDR highlight).
    fast = _block_inside(geo, cell, x0 - 1, y0 - 1, x0 + 2, y0 + 2)
    wx0, wx1, wx2, wx3 = _cubic_weights(tx)
    wy0, wy1, wy2, wy3 = _cubic_weights(ty)
    for c in range(nch):
        tmp[c] = 0.0
        tmp[nch + c] = math.inf
        tmp[2 * nch + c] = -math.inf
    for k in range(4):
        wy = wy0 if k == 0 else (wy1 if k == 1 else (wy2 if k == 2 else wy3))
        for m in range(4):
            wx = wx0 if m == 0 else (wx1 if m == 1 else (wx2 if m == 2 else wx3))
            jx, jy = _fetch(
                src, geo, cell_face, cell_turns, face_cell, cell, x0 - 1 + m, y0 - 1 + k, fast
            )
            central = (k == 1 or k == 2) and (m == 1 or m == 2)
            for c in range(nch):
                v = src[jy, jx, c]
                tmp[c] += wx * wy * v
                if central:
                    tmp[nch + c] = min(tmp[nch + c], v)
                    tmp[2 * nch + c] = max(tmp[2 * nch + c], v)
    for c in range(nch):
        acc[c] += w * min(max(tmp[c], tmp[nch + c]), tmp[2 * nch + c])
