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

from .base import FAMILY_ANGULAR, Cell, Layout

__all__ = ["LAYOUT"]

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
