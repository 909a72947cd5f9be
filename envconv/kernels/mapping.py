"""Kernels that map between image points and directions, one point at a time.

Used by :mod:`envconv.geometry` (uv ↔ direction, pixel solid angles) and by the resampling and
mip kernels (:func:`output_sample`, :func:`source_point`). Geometry arrives as (geo, cell_face, cell_turns, face_cell);
see :mod:`envconv.kernels.cells`. Image points are level-0 pixels.
"""


from .._jit import jit_inline, jit_parallel, prange
from .cells import (
    GEO_FAMILY,
    cell_local,
    face_to_image,
    locate,
    nearest_cell,
    point_readable,
    point_valid,
)
from .geometry import density, dir_to_face, face_to_dir

__all__ = [
    "output_sample",
    "source_point",
    "map_points_to_dirs",
    "map_dirs_to_points",
    "pixel_solid_angles",
    "dir_density",
]


@jit_inline
def output_sample(dgeo, d_cell_face, d_cell_turns, px, py, fill):
    """(face, a, b, readable, valid) of output image point (px, py); fill extends readability."""
    face, a, b, cell = locate(dgeo, d_cell_face, d_cell_turns, px, py)
    valid = point_valid(dgeo, face, a, b)
    if valid or point_readable(dgeo, face, a, b):
        return face, a, b, True, valid
    if not fill:
        return face, a, b, False, False
    cell = nearest_cell(dgeo, d_cell_face, px, py)
    a, b = cell_local(dgeo, d_cell_turns, cell, px, py)
    return d_cell_face[cell], a, b, True, False


@jit_inline
def source_point(sgeo, s_face_cell, s_cell_turns, dfam, face, a, b, rot):
    """Source image point and cell of output point (a, b) of ``face``, after rotation."""
    x, y, z = face_to_dir(dfam, face, a, b)
    xs = rot[0, 0] * x + rot[0, 1] * y + rot[0, 2] * z
    ys = rot[1, 0] * x + rot[1, 1] * y + rot[1, 2] * z
    zs = rot[2, 0] * x + rot[2, 1] * y + rot[2, 2] * z
    sface, sa, sb = dir_to_face(sgeo[GEO_FAMILY], xs, ys, zs)
    return face_to_image(sgeo, s_face_cell, s_cell_turns, sface, sa, sb)


@jit_parallel
def map_points_to_dirs(geo, cell_face, cell_turns, points, fill, dirs, flags):
    """Directions of level-0 image points (n, 2); flags: 2 valid, 1 guard/fill, 0 no data."""
    fam = geo[GEO_FAMILY]
    for k in prange(points.shape[0]):
        face, a, b, readable, valid = output_sample(
            geo, cell_face, cell_turns, points[k, 0], points[k, 1], fill
        )
        if readable:
            x, y, z = face_to_dir(fam, face, a, b)
            dirs[k, 0], dirs[k, 1], dirs[k, 2] = x, y, z
        else:
            dirs[k, 0], dirs[k, 1], dirs[k, 2] = 0.0, 0.0, 0.0
        flags[k] = 2 if valid else (1 if readable else 0)


@jit_parallel
def map_dirs_to_points(geo, cell_turns, face_cell, dirs, points):
    """Level-0 image points (n, 2) of unit directions (n, 3)."""
    fam = geo[GEO_FAMILY]
    for k in prange(dirs.shape[0]):
        face, a, b = dir_to_face(fam, dirs[k, 0], dirs[k, 1], dirs[k, 2])
        px, py, cell = face_to_image(geo, face_cell, cell_turns, face, a, b)
        points[k, 0] = px
        points[k, 1] = py


@jit_parallel
def pixel_solid_angles(geo, cell_face, cell_turns, scale_x, scale_y, samples, out):
    """Solid angle (sr) of the valid part of every pixel of an (H, W) image, by S×S sub-samples."""
    height, width = out.shape
    fam = geo[GEO_FAMILY]
    n = geo[1]
    aspect = geo[3]
    # Area of one sub-sample in (a, b) units.
    sub_area = (2.0 * scale_x / (aspect * n)) * (2.0 * scale_y / n) / (samples * samples)
    for j in prange(height):
        for i in range(width):
            total = 0.0
            for sy in range(samples):
                py = (j + (sy + 0.5) / samples) * scale_y
                for sx in range(samples):
                    px = (i + (sx + 0.5) / samples) * scale_x
                    face, a, b, cell = locate(geo, cell_face, cell_turns, px, py)
                    if point_valid(geo, face, a, b):
                        total += density(fam, face, a, b) * sub_area
            out[j, i] = total


@jit_inline
def dir_density(geo, dirs, out):
    """Solid-angle density of the layout at each direction's (face, a, b)."""
    fam = geo[GEO_FAMILY]
    for k in range(dirs.shape[0]):
        face, a, b = dir_to_face(fam, dirs[k, 0], dirs[k, 1], dirs[k, 2])
        out[k] = density(fam, face, a, b)
