"""Sources that cover part of the sphere (a fisheye of fov < 360, a perspective view): the
directions they do not cover are holes.

The resampling kernel maps every direction into its source. A partial layout's
``dir_to_face`` sends a direction it does not cover past its valid region, no further than its
*reach* (:meth:`envconv.layouts.base.Layout.kernel_params`): the middle of a ring of
:data:`~envconv.layouts.base.PARTIAL_PAD` pixels that :func:`pad_partial` adds around every
cell, as a guard ring. The padded map's ``valid`` is 1 where the source covers (the cell's
valid region: a fisheye's disk, a perspective view's rectangle, less any hole the file already
had) and 0 elsewhere: its own guard ring, a fisheye's corners past the rim, the pad. The holes
machinery (:mod:`envconv.resample.holes`) then resamples ``valid`` with the colour: a pixel
wholly outside the view is 0 with coverage 0, a pixel across the view's edge is the mean of its
covered samples, and ``alpha=True`` gives the covered part of each pixel.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..envmap import EnvMap
from ..layouts.base import PARTIAL_PAD

__all__ = ["pad_partial", "covered_mask"]


def covered_mask(layout, n: int, guard: int) -> np.ndarray:
    """(H, W) float32: 1 at the pixels of a ``layout`` image (size ``n``, guard ``guard``) whose
    centres lie in a cell's valid region, 0 elsewhere."""
    width, height = layout.image_size(n, guard)
    cw, ch = layout.cell_size(n, guard)
    nx = layout.content_width(n)
    mask = np.zeros((height, width), np.float32)
    x = (np.arange(cw) + 0.5 - guard) * (2.0 / nx) - 1.0
    y = (np.arange(ch) + 0.5 - guard) * (2.0 / n) - 1.0
    if layout.disk:
        inside = (x[None, :] ** 2 + y[:, None] ** 2) <= 1.0
    else:
        inside = (np.abs(x[None, :]) <= 1.0) & (np.abs(y[:, None]) <= 1.0)
    for cell in layout.cells:
        mask[cell.row * ch : (cell.row + 1) * ch, cell.col * cw : (cell.col + 1) * cw] = inside
    return mask


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
