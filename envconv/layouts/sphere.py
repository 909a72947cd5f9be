"""sphere: the mirror ball (OpenGL GL_SPHERE_MAP, USD ``mirroredBall``), N × N.

::

          +----------------+        what an orthographic camera looking along -Z sees
          |   .--------.   |        in a mirror ball: +Z at the centre, -Z on the rim
          | /     +Y     \\ |
          ||-X    +Z   +X ||        X = 2u - 1, Y = 1 - 2v, R² = X² + Y² <= 1
          | \\     -Y     / |        n_z = sqrt(1 - R²)
          |   '--------'   |        d = (2 n_z X, 2 n_z Y, 2 n_z² - 1)
          +----------------+

Inverse: m = 2 sqrt(x² + y² + (z + 1)²), u = 0.5 + x/m, v = 0.5 - y/m. Valid region: the unit
disk. Continued mapping past the rim (1 < R <= 2): alpha = 2π - 2 asin(2 - R) in
d = (sin alpha X/R, sin alpha Y/R, cos alpha), i.e. the inside point at radius 2 - R on the
opposite azimuth (the great circle continued through -Z); beyond R = 2, R = 2.
The solid angle per unit disk area is 4 sr inside the disk.
"""

import math

from .._jit import jit
from .base import FAMILY_SPHERE, Cell, Layout

__all__ = ["LAYOUT", "face_to_dir", "dir_to_face", "density"]

LAYOUT = Layout(
    name="sphere",
    family=FAMILY_SPHERE,
    description="mirror ball N x N (GL_SPHERE_MAP, USD mirroredBall): +Z centre, -Z on the rim",
    columns=1,
    rows=1,
    aspect=1,
    cells=(Cell(0, 0, 0),),
    face_names=("sphere",),
)


@jit
def face_to_dir(face, a, b):
    """Direction of disk point (a, b) = (X, -Y), continued past the rim."""
    X, Y = a, -b
    r2 = X * X + Y * Y
    if r2 <= 1.0:
        nz = math.sqrt(1.0 - r2)
        return 2.0 * nz * X, 2.0 * nz * Y, 2.0 * nz * nz - 1.0
    r = math.sqrt(r2)
    rc = min(r, 2.0)
    alpha = 2.0 * math.pi - 2.0 * math.asin(2.0 - rc)
    s = math.sin(alpha) / r
    return s * X, s * Y, math.cos(alpha)


@jit
def dir_to_face(x, y, z):
    """(0, a, b) of a direction; -Z itself lands on the rim at a = 1."""
    # (a, b) = (x, -y) / |d + Z|; hypot keeps precision when the components' squares are
    # subnormal (d within 1e-154 of -Z), and tiny components are scaled up by an exact power of
    # two first because the kernels' fast-math may divide by multiplying with 1/|d + Z|.
    zp = z + 1.0
    m = math.hypot(math.hypot(x, y), zp)
    if m == 0.0:
        return 0, 1.0, 0.0
    if m < 1e-150:
        x *= 2.0**600
        y *= 2.0**600
        zp *= 2.0**600
        m = math.hypot(math.hypot(x, y), zp)
    return 0, x / m, -y / m


@jit
def density(face, a, b):
    """Solid angle per unit (a, b) area: 4 inside the disk, 4(2 - R)/R past the rim (sr)."""
    r = math.sqrt(a * a + b * b)
    if r <= 1.0:
        return 4.0
    return 4.0 * max(2.0 - r, 1e-6) / r
