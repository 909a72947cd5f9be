"""cube-vcross: the HDRShop / CubeMapGen / cmft vertical cross, 3N × 4N.

::

          +------+
          | +Y_c |            middle row reads world +X, +Z, -X
    +-----+------+-----+      (the cross unwraps the lat-long unmirrored)
    | -X_c| +Z_c | +X_c|
    +-----+------+-----+      -Z_c is stored rotated 180°, so the edge it
          | -Y_c |            shares with -Y_c is continuous
          +------+
          | -Z_c |  (rotated 180°)
          +------+

Faces follow the GL/D3D/KTX table of :mod:`envconv.layouts.cube`. The six empty cells are
invalid (alpha 0, colour 0 unless a guard ring or ``--guard fill`` covers them).
"""

from .base import FAMILY_CUBE_GL, Cell, Layout
from .cube import FACE_NAMES

__all__ = ["LAYOUT"]

LAYOUT = Layout(
    name="cube-vcross",
    family=FAMILY_CUBE_GL,
    description="vertical cross 3N x 4N (HDRShop/CubeMapGen/cmft), -Z rotated 180 degrees",
    columns=3,
    rows=4,
    aspect=1,
    cells=(
        Cell(1, 0, 2),
        Cell(0, 1, 1),
        Cell(1, 1, 4),
        Cell(2, 1, 0),
        Cell(1, 2, 3),
        Cell(1, 3, 5, turns=2),
    ),
    face_names=FACE_NAMES,
)
