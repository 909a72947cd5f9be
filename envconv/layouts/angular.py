"""angular: Debevec's light probe (USD ``angular``), N × N.

::

          +----------------+        same centre and orientation as the sphere map,
          |   .--------.   |        but the radius is linear in angle:
          | /     +Y     \\ |        alpha = π R from +Z, R = 1 is -Z
          ||-X    +Z   +X ||
          | \\     -Y     / |        d = (sin alpha X/R, sin alpha Y/R, cos alpha)
          |   '--------'   |        X = 2u - 1, Y = 1 - 2v
          +----------------+

Inverse: R = acos(z)/π along the azimuth of (x, y). Valid region: the unit disk. Continued
mapping: alpha = π R past R = 1. Solid angle per unit area: π sin(π R)/R.
"""

import math

from .._jit import jit
from .base import FAMILY_ANGULAR, Cell, Layout

__all__ = ["LAYOUT", "face_to_dir", "dir_to_face", "density"]

LAYOUT = Layout(
    name="angular",
    family=FAMILY_ANGULAR,
    description="angular light probe N x N (Debevec): radius linear in angle, -Z on the rim",
    columns=1,
    rows=1,
    aspect=1,
    cells=(Cell(0, 0, 0),),
    face_names=("angular",),
)


@jit
def face_to_dir(face, a, b):
    """Direction of disk point (a, b) = (X, -Y), continued past the rim."""
    X, Y = a, -b
    r = math.sqrt(X * X + Y * Y)
    if r < 1e-12:
        return 0.0, 0.0, 1.0
    alpha = math.pi * r
    s = math.sin(alpha) / r
    return s * X, s * Y, math.cos(alpha)


@jit
def dir_to_face(x, y, z):
    """(0, a, b) of a direction; -Z lands on the rim at a = 1."""
    # atan2 keeps full precision near the centre, where acos(z) loses half the digits, and
    # hypot keeps it for subnormal components.
    r_xy = math.hypot(x, y)
    rad = math.atan2(r_xy, z) / math.pi
    if r_xy == 0.0:
        if z >= 0.0:
            return 0, 0.0, 0.0
        return 0, 1.0, 0.0
    if r_xy < 1e-150:
        # Scale tiny (x, y) up by an exact power of two before dividing by their length: the
        # kernels' fast-math may divide by multiplying with 1/r_xy, which overflows here.
        x *= 2.0**600
        y *= 2.0**600
        r_xy = math.hypot(x, y)
    return 0, rad * (x / r_xy), -rad * (y / r_xy)


@jit
def density(face, a, b):
    """Solid angle per unit (a, b) area: π |sin(π R)| / R (sr); π² at the centre."""
    r = math.sqrt(a * a + b * b)
    if r < 1e-9:
        return math.pi * math.pi
    return math.pi * abs(math.sin(math.pi * r)) / r
