"""cube-exr: OpenEXR's own cube map (``envmap = cube``), an N × 6N vertical strip.

::

    +-----+
    | +X  |   faces top to bottom: +X, -X, +Y, -Y, +Z, -Z (world frame)
    +-----+
    | -X  |   each an unmirrored inside view; texel (a, b), a right, b down:
    +-----+     +X ( 1, -b,  a)    -X (-1, -b, -a)
    | +Y  |     +Y ( a,  1, -b)    -Y ( a, -1,  b)
    +-----+     +Z (-a, -b,  1)    -Z ( a, -b, -1)
    | -Y  |
    +-----+   Every cell is valid. Continued mapping: the face plane past ±1.
    | +Z  |   Exact ties between axes go to x, then y, then z; zero counts as positive.
    +-----+
    | -Z  |
    +-----+
"""

from .base import FAMILY_CUBE_EXR, Cell, Layout

__all__ = ["LAYOUT"]

LAYOUT = Layout(
    name="cube-exr",
    family=FAMILY_CUBE_EXR,
    description="OpenEXR envcube: N x 6N strip of world faces +X -X +Y -Y +Z -Z (envmap=cube)",
    columns=1,
    rows=6,
    aspect=1,
    cells=tuple(Cell(0, i, i) for i in range(6)),
    face_names=("px", "nx", "py", "ny", "pz", "nz"),
)
