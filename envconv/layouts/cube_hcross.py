"""cube-hcross: the horizontal cross, 4N × 3N.

::

          +------+
          | +Y_c |
    +-----+------+-----+------+     middle row reads world +X, +Z, -X, -Z,
    | -X_c| +Z_c | +X_c| -Z_c |     as the lat-long does; the wrap from -Z_c
    +-----+------+-----+------+     back to -X_c is continuous too
          | -Y_c |
          +------+

Faces follow the GL/D3D/KTX table of :mod:`envconv.layouts.cube`; none is rotated. The six
empty cells are invalid.
"""

from .base import FAMILY_CUBE_GL, Cell, Layout
from .cube import FACE_NAMES

__all__ = ["LAYOUT"]

LAYOUT = Layout(
    name="cube-hcross",
    family=FAMILY_CUBE_GL,
    description="horizontal cross 4N x 3N, middle row +X +Z -X -Z like the lat-long",
    columns=4,
    rows=3,
    aspect=1,
    cells=(
        Cell(1, 0, 2),
        Cell(0, 1, 1),
        Cell(1, 1, 4),
        Cell(2, 1, 0),
        Cell(3, 1, 5),
        Cell(1, 2, 3),
    ),
    face_names=FACE_NAMES,
)
