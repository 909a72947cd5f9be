"""Sources that cover part of the sphere (a fisheye of fov < 360, a perspective view): the
directions they do not cover are holes.

The resampling kernel maps every direction into its source. A partial layout's
``dir_to_face`` sends a direction it does not cover past its valid region, no further than its
*reach* (:meth:`envconv.layouts.base.Layout.kernel_params`): the middle of a ring of
:data:`~envconv.layouts.base.PARTIAL_PAD` pixels that :func:`pad_partial` adds around every
cell, as a guard ring. The padded map's ``valid`` is the part of each pixel the source covers
(the cell's valid region: a fisheye's disk, a perspective view's rectangle, less any hole the
file already had): 1 inside, the covered fraction across a fisheye's rim, 0 elsewhere (its own
guard ring, a fisheye's corners, the pad), and the pixels hold colour × valid. The holes
machinery (:mod:`envconv.resample.holes`) then resamples ``valid`` with the colour: a pixel
wholly outside the view is 0 with coverage 0, a pixel across the view's edge is the mean of its
covered samples, and ``alpha=True`` gives the covered part of each pixel.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..envmap import EnvMap
from ..layouts.base import PARTIAL_PAD

__all__ = ["pad_partial", "covered_mask"]


#: Sub-columns across a pixel the rim crosses, in which the covered part of each column is
#: exact (between the rim's two heights); the density is taken at 3 Gauss points of it.
RIM_COLUMNS = 64
_GAUSS = (
    np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)]) * 0.5 + 0.5,
    np.array([5.0, 8.0, 5.0]) / 18.0,
)


def covered_mask(layout, n: int, guard: int) -> np.ndarray:
    """(H, W) float32: the part of each pixel of a ``layout`` image (size ``n``, guard
    ``guard``) inside its cell's valid region: 1 or 0, and for a pixel across a disk's rim the
    covered part of its solid angle (so that the pixel's colour × valid, spread over the whole
    pixel, holds the energy of its covered part: what the area filter keeps)."""
    width, height = layout.image_size(n, guard)
    cw, ch = layout.cell_size(n, guard)
    nx = layout.content_width(n)
    mask = np.zeros((height, width), np.float32)
    for cell in layout.cells:
        if layout.disk:
            inside = _disk_cover(layout, cell.face, cw, ch, n, guard)
        else:
            x = (np.arange(cw) + 0.5 - guard) * (2.0 / nx) - 1.0
            y = (np.arange(ch) + 0.5 - guard) * (2.0 / n) - 1.0
            inside = (np.abs(x[None, :]) <= 1.0) & (np.abs(y[:, None]) <= 1.0)
        mask[cell.row * ch : (cell.row + 1) * ch, cell.col * cw : (cell.col + 1) * cw] = inside
    return mask


def _disk_cover(layout, face: int, cw: int, ch: int, n: int, guard: int) -> np.ndarray:
    """(ch, cw) float32: the part of each pixel of a disk cell (diameter n, guard ring guard)
    inside the disk, weighted by solid angle; integrated only for the pixels the rim crosses:
    RIM_COLUMNS sub-columns, each's covered interval exact, the layout's density at 3 Gauss
    points of it and of the whole column."""
    scale = 2.0 / n
    x0 = (np.arange(cw) - guard) * scale - 1.0  # each pixel's left edge, in (a, b)
    y0 = (np.arange(ch) - guard) * scale - 1.0
    # The nearest and farthest points of each pixel from the centre.
    near_x = np.maximum(0.0, np.maximum(x0, -(x0 + scale)))
    near_y = np.maximum(0.0, np.maximum(y0, -(y0 + scale)))
    far_x = np.maximum(np.abs(x0), np.abs(x0 + scale))
    far_y = np.maximum(np.abs(y0), np.abs(y0 + scale))
    near = near_x[None, :] ** 2 + near_y[:, None] ** 2
    far = far_x[None, :] ** 2 + far_y[:, None] ** 2
    cover = (far <= 1.0).astype(np.float32)
    rim = np.nonzero((near < 1.0) & (far > 1.0))
    nodes, weights = _GAUSS
    sx = x0[rim[1]][:, None] + (np.arange(RIM_COLUMNS) + 0.5) / RIM_COLUMNS * scale  # (R, C)
    top = y0[rim[0]][:, None]
    half = np.sqrt(np.maximum(1.0 - sx * sx, 0.0))
    lo, hi = np.clip(-half, top, top + scale), np.clip(half, top, top + scale)
    whole = covered = 0.0
    for t, w in zip(nodes, weights, strict=True):
        whole = whole + w * scale * layout.density(face, sx, top + t * scale)
        covered = covered + w * (hi - lo) * layout.density(face, sx, lo + t * (hi - lo))
    cover[rim] = covered.sum(axis=1) / whole.sum(axis=1)
    return cover


def pad_partial(envmap: EnvMap) -> EnvMap:
    """``envmap`` (a partial layout's map) with a ring of PARTIAL_PAD hole pixels around every
    cell, its guard grown by as much, and ``valid`` 0 wherever it does not cover (see the module
    docstring). Its MIP levels, if any, are dropped: only level 0 is resampled."""
    layout, n, guard = envmap.layout, envmap.size, envmap.guard
    grown = guard + PARTIAL_PAD
    width, height = layout.image_size(n, grown)
    cw, ch = layout.cell_size(n, guard)
    gw, gh = layout.cell_size(n, grown)
    pixels = np.zeros((height, width, envmap.pixels.shape[2]), np.float32)
    valid = np.zeros((height, width), np.float32)
    held = covered_mask(layout, n, guard)
    if envmap.valid is not None:
        held = held * envmap.valid
    for cell in layout.cells:
        src = (slice(cell.row * ch, (cell.row + 1) * ch), slice(cell.col * cw, (cell.col + 1) * cw))
        y0, x0 = cell.row * gh + PARTIAL_PAD, cell.col * gw + PARTIAL_PAD
        dst = (slice(y0, y0 + ch), slice(x0, x0 + cw))
        pixels[dst] = envmap.pixels[src] * held[src][:, :, None]  # holes hold 0 (holes.py)
        valid[dst] = held[src]
    return dataclasses.replace(envmap, pixels=pixels, guard=grown, valid=valid, levels=None)
