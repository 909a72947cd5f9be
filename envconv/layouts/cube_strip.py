"""cube-hstrip (6N × N) and cube-vstrip (N × 6N): the six GL faces in face order.

::

    cube-hstrip:  +------+------+------+------+------+------+
                  | +X_c | -X_c | +Y_c | -Y_c | +Z_c | -Z_c |
                  +------+------+------+------+------+------+

    cube-vstrip:  the same six cells stacked top to bottom.

Faces follow the GL/D3D/KTX table of :mod:`envconv.layouts.cube` (+X_c is world -X). Every cell
is valid.
"""

from .base import FAMILY_CUBE_GL, Cell, Layout
from .cube import FACE_NAMES

__all__ = ["HSTRIP", "VSTRIP"]

HSTRIP = Layout(
    name="cube-hstrip",
    family=FAMILY_CUBE_GL,
    description="horizontal strip 6N x N of GL faces +X_c -X_c +Y_c -Y_c +Z_c -Z_c",
    columns=6,
    rows=1,
    aspect=1,
    cells=tuple(Cell(i, 0, i) for i in range(6)),
    face_names=FACE_NAMES,
)

VSTRIP = Layout(
    name="cube-vstrip",
    family=FAMILY_CUBE_GL,
    description="vertical strip N x 6N of GL faces +X_c -X_c +Y_c -Y_c +Z_c -Z_c",
    columns=1,
    rows=6,
    aspect=1,
    cells=tuple(Cell(0, i, i) for i in range(6)),
    face_names=FACE_NAMES,
)
