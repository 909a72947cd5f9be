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

from .base import FAMILY_SPHERE, Cell, Layout

__all__ = ["LAYOUT"]

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
