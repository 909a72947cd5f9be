"""The small interface every layout implements.

A layout is a grid of equal cells laid over the image. Each cell holds one *face*: a square or
rectangular chart of directions with local coordinates (a, b) in [-1, 1]², a to the right and b
downward. The maps of the layout's geometry family, which turn (face, a, b) into a direction and
back, live once, in the native core (``src/core/layouts.h``), and reach Python as the vectorised
:meth:`Layout.face_to_dir`, :meth:`Layout.dir_to_face` and :meth:`Layout.density`; this module
holds the Python-side description (size rule, cell placement, files).

Pixel-centre rule: pixel (i, j) of a W×H image covers [i/W, (i+1)/W] × [j/H, (j+1)/H] and its
centre is at ((i + 0.5)/W, (j + 0.5)/H). With a guard ring of G pixels every cell grows by G on
each side; inside a grown cell whose top-left pixel is (x0, y0),
``a = 2 (x + 0.5 - x0 - G) / (aspect N) - 1`` and ``b = 2 (y + 0.5 - y0 - G) / N - 1``.

Aimed layouts (fisheye, perspective) carry their view, the field of view and the view frame, in
``params`` (the chart's parameters, passed to the core's maps) and ``view`` (the options as
given, for metadata and messages); :meth:`Layout.configure` makes one from options. A layout
that covers only part of the sphere is ``partial``: as a source, the directions it does not
cover are holes (:mod:`envconv.resample.partial`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import LayoutError, UsageError

# Geometry family codes: the native core's own (src/core/chart.h, exported by
# src/core/module.cpp), which its kernels dispatch on; never restated here.
from ..resample.kernels import (
    DISK_FAMILIES,
    FAMILY_ANGULAR,
    FAMILY_CUBE_EXR,
    FAMILY_CUBE_GL,
    FAMILY_EAC,
    FAMILY_EQUAL_AREA,
    FAMILY_FISHEYE,
    FAMILY_LATLONG,
    FAMILY_OCTAHEDRAL,
    FAMILY_PARABOLOID,
    FAMILY_PERSPECTIVE,
    FAMILY_SPHERE,
    FAMILY_TENNISBALL,
    PARAM_COUNT,
)

__all__ = [
    "Cell",
    "Layout",
    "FAMILY_LATLONG",
    "FAMILY_CUBE_GL",
    "FAMILY_CUBE_EXR",
    "FAMILY_SPHERE",
    "FAMILY_ANGULAR",
    "FAMILY_PARABOLOID",
    "FAMILY_TENNISBALL",
    "FAMILY_OCTAHEDRAL",
    "FAMILY_EQUAL_AREA",
    "DISK_FAMILIES",
    "FAMILY_EAC",
    "FAMILY_FISHEYE",
    "FAMILY_PERSPECTIVE",
    "PARAM_COUNT",
    "PARTIAL_PAD",
    "VIEW_OPTIONS",
]

#: Index of the reach among a chart's PARAM_COUNT parameters (src/core/chart.h kReach).
_REACH = 11
#: Pixels of holes a partial source is padded with, around its cells (its guard ring grows by
#: as much); directions it does not cover land in the middle of that ring (its reach).
PARTIAL_PAD = 6
#: The options an aimed layout takes (:meth:`Layout.configure`).
VIEW_OPTIONS = ("fov", "yaw", "pitch", "roll")


@dataclass(frozen=True)
class Cell:
    """One occupied cell: grid column and row, the face it holds, and its rotation.

    ``turns`` counts half turns (0 or 2 quarter turns): 2 means the face is stored rotated by
    180°, so the cell's local (a', b') is the face's (-a, -b).
    """

    col: int
    row: int
    face: int
    turns: int = 0


@dataclass(frozen=True)
class Layout:
    """Description of one layout: its grid, cells, size rule and files.

    Attributes
    ----------
    name : str
        Registry name, e.g. ``"cube-vcross"``.
    family : int
        Geometry family code (``FAMILY_*``) whose native maps take (face, a, b) ↔ direction.
    description : str
        One line for ``envconv layouts``.
    columns, rows : int
        Grid of cells, in cells.
    aspect : int or float
        Cell width in units of N (the cell height is always N): 2 for lat-long, 3 for
        tennisball; a perspective view's width / height.
    cells : tuple of Cell
        Occupied cells; grid cells not listed hold no face and are invalid.
    face_names : tuple of str
        Names of the faces, in face-index order (also the file-part names of multi-file layouts).
    multi_file : bool
        True when the layout is stored as one file per cell, named with ``{face}``.
    params : tuple of float
        The chart's parameters for the core's maps (``PARAM_COUNT`` of them, or none for a
        family that takes none).
    view : tuple of (str, object)
        An aimed layout's options (``fov``, ``yaw``, ``pitch``, ``roll``), as
        :meth:`configure` resolved them; empty for the others.
    partial : bool
        True when the layout covers only part of the sphere.
    configurer : callable, optional
        ``configurer(layout, fov=, yaw=, pitch=, roll=, width=, height=)``: the layout module's
        rule for a configured copy (:meth:`configure`); None for a layout without options.
    """

    name: str
    family: int
    description: str
    columns: int
    rows: int
    aspect: int | float
    cells: tuple[Cell, ...]
    face_names: tuple[str, ...]
    multi_file: bool = False
    params: tuple[float, ...] = ()
    view: tuple[tuple[str, Any], ...] = ()
    partial: bool = False
    configurer: Callable[..., Layout] | None = field(default=None, compare=False, repr=False)

    def configure(self, **options: Any) -> Layout:
        """A copy of this layout with view options (``fov``, ``yaw``, ``pitch``, ``roll``) and,
        for a perspective view, its ``width`` and ``height`` in pixels; options left None keep
        their value. UsageError for an option the layout does not take or a bad value."""
        given = {k: v for k, v in options.items() if v is not None}
        if self.configurer is None:
            if given:
                names = ", ".join(f"--{k}" for k in given)
                raise UsageError(f"{names} applies to the aimed layouts (fisheye, perspective), "
                                 f"not to {self.name}")  # fmt: skip
            return self
        return self.configurer(self, **given)

    @property
    def view_options(self) -> dict[str, Any]:
        """The view options as a dict (empty for layouts without a view)."""
        return dict(self.view)

    def kernel_params(self, n: int | None = None, guard: int = 0,
                      output: bool = False) -> np.ndarray:  # fmt: skip
        """The chart's ``PARAM_COUNT`` parameters for the core; a partial layout's reach puts
        uncovered directions in the middle of a guard ring padded by :data:`PARTIAL_PAD`.

        ``output``: the parameters of an image being made, whose reach takes in the whole
        image, guard ring and ``--guard fill`` corners included (the area filter finds where a
        source's pole lands in an output pixel by the inverse map: a reach at the view's edge
        would put a pole in the ring on that edge): a fisheye's π / h (no angle is clamped), a
        perspective view's twice its grown image's half-extent."""
        params = np.zeros(PARAM_COUNT)
        params[: len(self.params)] = self.params
        if self.partial and n and output:
            if self.family == FAMILY_FISHEYE:
                params[_REACH] = np.pi / params[0]
            else:
                params[_REACH] = 2.0 * (1.0 + 2.0 * guard / min(n, self.content_width(n)))
        elif self.partial and n:
            params[_REACH] = 1.0 + 2.0 * max(guard - PARTIAL_PAD // 2, 0) / n
        return params

    def content_width(self, n: int) -> int:
        """N_x: a cell's width in pixels without guard, aspect × N (rounded: a perspective
        view's aspect is its own width : height)."""
        return int(round(self.aspect * n))

    @property
    def disk(self) -> bool:
        """True when each cell's valid region is the unit disk rather than the whole cell."""
        return self.family in DISK_FAMILIES

    @property
    def n_faces(self) -> int:
        return len(self.face_names)

    def cell_size(self, n: int, guard: int = 0) -> tuple[int, int]:
        """Width and height in pixels of one (grown) cell."""
        return self.content_width(n) + 2 * guard, n + 2 * guard

    def image_size(self, n: int, guard: int = 0) -> tuple[int, int]:
        """Image width and height in pixels for characteristic size ``n`` and guard ``guard``.

        For multi-file layouts this is the size of the in-memory mosaic (all cells side by side).
        """
        cw, ch = self.cell_size(n, guard)
        return self.columns * cw, self.rows * ch

    def file_size(self, n: int, guard: int = 0) -> tuple[int, int]:
        """Size of each file on disk (one cell for multi-file layouts)."""
        return self.cell_size(n, guard) if self.multi_file else self.image_size(n, guard)

    def size_from_image(self, width: int, height: int, guard: int = 0) -> int:
        """Characteristic size N of a ``width`` × ``height`` image, or raise LayoutError."""
        if height % self.rows or width % self.columns:
            raise LayoutError(self._misfit(width, height, guard))
        cw, ch = width // self.columns, height // self.rows
        n = ch - 2 * guard
        if n < 1 or cw != self.content_width(n) + 2 * guard:
            raise LayoutError(self._misfit(width, height, guard))
        return n

    def _misfit(self, width: int, height: int, guard: int) -> str:
        w1, h1 = self.image_size(1, 0)
        rule = (
            f"{w1}N x {h1}N" if not guard else f"cells of ({self.aspect}N+2G) x (N+2G), G={guard}"
        )
        return f"image is {width}x{height}, which does not fit layout {self.name} ({rule}); pass --from"

    def validate_size(self, n: int) -> None:
        """Raise LayoutError unless ``n`` is a usable characteristic size."""
        if not isinstance(n, (int, np.integer)) or n < 1:
            raise LayoutError(f"size must be a positive integer, got {n!r}")

    def face_to_dir(self, face, a, b) -> np.ndarray:
        """Unit directions (..., 3) of local points (a, b) of ``face`` (arrays broadcast),
        continued past the valid region as guard rings and filter taps read it."""
        from ..resample.kernels import face_to_dir

        return face_to_dir(self.family, face, a, b, self.kernel_params())

    def dir_to_face(self, dirs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(face, a, b) of unit directions (..., 3), with (a, b) in the face's valid region."""
        from ..resample.kernels import dir_to_face

        return dir_to_face(self.family, dirs, self.kernel_params())

    def density(self, face, a, b) -> np.ndarray:
        """Solid angle per unit (a, b) area, in steradians, at local points of ``face``."""
        from ..resample.kernels import density

        return density(self.family, face, a, b, self.kernel_params())

    def kernel_tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Integer tables the kernels read: cell → face, cell → turns, face → cell.

        Cells are indexed ``row * columns + col``; an empty cell has face -1.
        """
        cell_face = np.full(self.columns * self.rows, -1, np.int32)
        cell_turns = np.zeros(self.columns * self.rows, np.int32)
        face_cell = np.zeros(max(self.n_faces, 1), np.int32)
        for cell in self.cells:
            index = cell.row * self.columns + cell.col
            cell_face[index] = cell.face
            cell_turns[index] = cell.turns
            face_cell[cell.face] = index
        return cell_face, cell_turns, face_cell
