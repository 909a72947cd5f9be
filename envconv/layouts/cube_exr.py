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

import math

from .._jit import jit
from .base import FAMILY_CUBE_EXR, Cell, Layout

__all__ = ["LAYOUT", "face_to_dir", "dir_to_face", "density"]

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


@jit
def face_to_dir(face, a, b):
    """Unit world direction of point (a, b) on OpenEXR cube face ``face`` (0..5)."""
    if face == 0:
        x, y, z = 1.0, -b, a
    elif face == 1:
        x, y, z = -1.0, -b, -a
    elif face == 2:
        x, y, z = a, 1.0, -b
    elif face == 3:
        x, y, z = a, -1.0, b
    elif face == 4:
        x, y, z = -a, -b, 1.0
    else:
        x, y, z = a, -b, -1.0
    inv = 1.0 / math.sqrt(x * x + y * y + z * z)
    return x * inv, y * inv, z * inv


@jit
def dir_to_face(x, y, z):
    """(face, a, b) of a direction, with a, b in [-1, 1]."""
    ax, ay, az = abs(x), abs(y), abs(z)
    if ax >= ay and ax >= az:
        if x >= 0.0:
            return 0, z / ax, -y / ax
        return 1, -z / ax, -y / ax
    if ay >= az:
        if y >= 0.0:
            return 2, x / ay, -z / ay
        return 3, x / ay, z / ay
    if z >= 0.0:
        return 4, -x / az, -y / az
    return 5, x / az, -y / az


@jit
def density(face, a, b):
    """Solid angle per unit area of (a, b) on a face: (1 + a² + b²)^(-3/2) (sr)."""
    r2 = 1.0 + a * a + b * b
    return 1.0 / (r2 * math.sqrt(r2))
