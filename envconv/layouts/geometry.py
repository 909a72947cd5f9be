"""Public pixel ↔ direction maps of every layout, vectorised over numpy arrays.

Coordinates follow docs/geometry.md: (u, v) in [0, 1]² of the whole image (u right, v down),
pixel centres at ((i + 0.5)/W, (j + 0.5)/H), world frame +Y up with +Z the lat-long centre.
For multi-file layouts (u, v) refer to the in-memory mosaic (cells side by side, face order).
"""

from __future__ import annotations

import math

import numpy as np

from ..resample import kernels
from . import Layout, get_layout

__all__ = [
    "kernel_geometry",
    "uv_to_dir",
    "dir_to_uv",
    "pixel_directions",
    "pixel_solid_angles",
    "horizon_pitch",
    "face_axes",
]


def kernel_geometry(layout: Layout | str, size: int, guard: int = 0, output: bool = False):
    """The (geo, cell_face, cell_turns, face_cell) arrays the kernels take: ``geo`` is
    [family, N, G, N_x, columns, rows, the chart's parameters] (float64). ``output``: an
    image being made, whose partial view's inverse map reaches over its whole image
    (:meth:`envconv.layouts.base.Layout.kernel_params`)."""
    layout = get_layout(layout)
    layout.validate_size(size)
    head = [layout.family, size, guard, layout.content_width(size), layout.columns, layout.rows]
    params = layout.kernel_params(size, guard, output)
    geo = np.concatenate([np.array(head, np.float64), params])
    return (geo, *layout.kernel_tables())


def uv_to_dir(layout, u, v, size: int = 512, guard: int = 0, fill: bool = False):
    """Directions of image points (u, v) of a layout of size N with guard G.

    Returns
    -------
    dirs : (..., 3) float64
        Unit directions; zero where the point holds no direction.
    flags : (...) int8
        2 in the valid region, 1 in a guard ring (or anywhere with ``fill``), 0 no data.
    """
    layout = get_layout(layout)
    width, height = layout.image_size(size, guard)
    u, v = np.broadcast_arrays(np.asarray(u, np.float64), np.asarray(v, np.float64))
    shape = u.shape
    points = np.stack([np.clip(u, 0.0, 1.0) * width, np.clip(v, 0.0, 1.0) * height], -1)
    points = np.ascontiguousarray(points.reshape(-1, 2))
    # u = 1 or v = 1 belongs to the last pixel (half-open intervals, docs/geometry.md).
    points[:, 0] = np.minimum(points[:, 0], np.nextafter(width, 0))
    points[:, 1] = np.minimum(points[:, 1], np.nextafter(height, 0))
    dirs, flags = kernels.map_points_to_dirs(kernel_geometry(layout, size, guard), points, fill)
    return dirs.reshape(*shape, 3), flags.reshape(shape)


def dir_to_uv(layout, dirs, size: int = 512, guard: int = 0):
    """(u, v) of unit directions (..., 3) in a layout of size N with guard G."""
    layout = get_layout(layout)
    width, height = layout.image_size(size, guard)
    dirs = np.asarray(dirs, np.float64)
    shape = dirs.shape[:-1]
    flat = np.ascontiguousarray(dirs.reshape(-1, 3))
    norm = np.linalg.norm(flat, axis=1, keepdims=True)
    flat = np.ascontiguousarray(flat / np.where(norm > 0, norm, 1.0))
    points = kernels.map_dirs_to_points(kernel_geometry(layout, size, guard), flat)
    u = np.clip(points[:, 0] / width, 0.0, 1.0).reshape(shape)
    v = np.clip(points[:, 1] / height, 0.0, 1.0).reshape(shape)
    return u, v


def pixel_directions(layout, size: int, guard: int = 0, fill: bool = False):
    """Directions (H, W, 3) and flags (H, W) of every pixel centre of a layout."""
    layout = get_layout(layout)
    width, height = layout.image_size(size, guard)
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    uu, vv = np.meshgrid(u, v)
    return uv_to_dir(layout, uu, vv, size, guard, fill)


def pixel_solid_angles(layout, size: int, guard: int = 0, samples: int = 4) -> np.ndarray:
    """Solid angle in steradians of the valid part of every pixel, (H, W) float64.

    Sums to 4π over a whole layout (up to the S×S sub-sampling error at disk rims).
    """
    layout = get_layout(layout)
    width, height = layout.image_size(size, guard)
    return kernels.pixel_solid_angles(
        kernel_geometry(layout, size, guard), 1.0, 1.0, samples, (height, width)
    )


def pixel_pitch(layout, dirs: np.ndarray) -> np.ndarray:
    """Angular pixel pitch (radians × N: √Ω of a pixel, for a layout of size N = 1) at each of
    the unit directions ``dirs`` (K, 3)."""
    layout = get_layout(layout)
    dens = kernels.dir_density(kernel_geometry(layout, 64, 0), dirs)
    # A pixel spans 2/(aspect N) × 2/N in (a, b).
    return np.sqrt(dens * 4.0 / float(layout.aspect))


def horizon_pitch(layout) -> float:
    """Mean angular pixel pitch (radians × N) along the horizon, for a layout of size N = 1.

    The pitch at a direction is √Ω of a pixel there. Averaged over 360 horizon directions, it
    is k in ``pitch = k / N``: π for lat-long, about 1.68 for cube faces. An aimed layout
    (fisheye, perspective), which may not see the horizon, gives its pitch at its view axis.
    """
    layout = get_layout(layout)
    if layout.view:
        axis = np.asarray(layout.params[2:11]).reshape(3, 3)[:, 2]  # the frame's third column
        return float(pixel_pitch(layout, axis[None, :])[0])
    phi = (np.arange(360) + 0.5) * (2 * math.pi / 360)
    dirs = np.stack([np.sin(phi), np.zeros_like(phi), np.cos(phi)], -1)
    return float(np.mean(pixel_pitch(layout, dirs)))


def face_axes(layout) -> list[tuple[str, str, int]]:
    """(face name, world axis, half turns) of each face of a cube layout, in face order.

    The axis (``+X`` … ``-Z``) is the direction the layout's own map gives the face's centre,
    (a, b) = (0, 0); the half turns (0, or 2 for 180°) are those of the face's cell. For the
    GL-table layouts ``px`` is world −X: their faces are +X_c … −Z_c of the left-handed cube
    frame c = (−x, y, z) (docs/geometry.md), each an unmirrored view from inside.
    """
    layout = get_layout(layout)
    faces = np.arange(layout.n_faces, dtype=np.int32)
    centres = np.zeros(len(faces))
    dirs = np.asarray(layout.face_to_dir(faces, centres, centres))
    turns = {cell.face: cell.turns for cell in layout.cells}
    axes = []
    for face, name, d in zip(faces, layout.face_names, dirs, strict=True):
        k = int(np.argmax(np.abs(d)))
        axes.append((name, ("+" if d[k] > 0 else "-") + "XYZ"[k], turns[int(face)]))
    return axes
