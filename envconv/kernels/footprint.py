"""How many sub-samples a pixel takes under ``samples="auto"``, and which rip-map level it reads.

The footprint of an output pixel is the number of source texels its edges span there, along
each axis: from a tile's grid (:mod:`envconv.kernels.tiles`) or, for exactly mapped pixels, from
the Jacobian at the pixel's centre (:func:`pixel_footprint`).
"""

import math

from .._jit import jit_inline
from .cells import GEO_FAMILY
from .geometry import density, dir_to_face, face_to_dir
from .mapping import output_sample, source_point

__all__ = [
    "AUTO_SPACING", "AUTO_SLACK", "AUTO_MAX_SAMPLES", "AUTO_EDGE_SAMPLES", "RIP_MIN_SPAN",
    "auto_count", "pixel_footprint", "rip_level", "level_span", "edge_y_part", "centre_source_y",
]  # fmt: skip


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
def rip_level(x_extent, levels):
    """Rip-map level for a footprint ``x_extent`` level-0 texels wide (see RIP_MIN_SPAN)."""
    level = 0
    while level < levels and RIP_MIN_SPAN * (2 << level) <= x_extent:
        level += 1
    return level


@jit_inline
def level_span(span, x_part, level):
    """Length in level-``level`` texels of an edge ``span`` level-0 texels long whose x
    component is ``x_part`` (levels shrink x by 2^level and keep y)."""
    if level == 0:
        return span
    shrink = 1.0 / (1 << level)
    return math.sqrt(max(span * span - x_part * x_part * (1.0 - shrink * shrink), 0.0))


@jit_inline
def edge_y_part(span, x_part):
    """Source-y component of an edge ``span`` texels long whose x component is ``x_part``."""
    return math.sqrt(max(span * span - x_part * x_part, 0.0))


@jit_inline
def centre_source_y(
    sgeo, s_face_cell, s_cell_turns, dgeo, d_cell_face, d_cell_turns, dfam,
    i, j, scale_x, scale_y, rot, fill,
):  # fmt: skip
    """Source row position of output pixel (i, j)'s centre (the middle row if it has none)."""
    face, a, b, readable, valid = output_sample(
        dgeo, d_cell_face, d_cell_turns, (i + 0.5) * scale_x, (j + 0.5) * scale_y, fill
    )
    if not readable:
        return 0.5 * sgeo[1]
    sx, sy, cell = source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot)
    return sy


@jit_inline
def auto_count(footprint):
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
        qface, qa, qb, readable, valid = output_sample(
            dgeo, d_cell_face, d_cell_turns, qx, qy, fill
        )
        if not readable or qface != face:
            continue
        sx, sy, cell = source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, qa, qb, rot)
        if cell != cell0:
            continue
        span = math.hypot(sx - sx0, sy - sy0) / delta
        if best < 0.0 or span < best:
            best = span
            best_x = abs(sx - sx0) / delta
    return best, best_x


@jit_inline
def pixel_footprint(
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
    face, a, b, readable, valid = output_sample(dgeo, d_cell_face, d_cell_turns, px, py, fill)
    if not readable:
        return -1.0, -1.0, -1.0, -1.0
    sx0, sy0, cell0 = source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot)
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
