"""tennisball: two 270° × 90° bands, like the two pieces of a tennis ball's cover; 3N × 2N.

::

    u_c=0                    u_c=0.5                  u_c=1
    +------------------------------------------------------+
    | C1: band about +Y, centred on +Z                     |  N rows: |lat| <= 45°,
    |   +X (1/6)            +Z             -X (5/6)        |  |lon| <= 135° of the lat-long
    +------------------------------------------------------+
    | C2: band about +X, centred on -Z                     |  N rows
    |   +Y (1/6)            -Z             -Y (5/6)        |
    +------------------------------------------------------+
    <------------------------ 3N ------------------------->

Within a band u_c = 0.5 - φ/(3π/2), v_c = 0.5 - θ/(π/2).
C1: θ = asin(y), φ = atan2(x, z); d = (sin φ cos θ, sin θ, cos φ cos θ).
C2: θ = asin(x), φ = atan2(y, -z); d = (sin θ, sin φ cos θ, -cos φ cos θ).
A direction belongs to C1 if (z >= 0 and |y| <= √2/2) or (z <= 0 and |x| >= √2/2), else to C2.
Every pixel of both bands is valid. Continued mapping: the same formulas past their ranges.
"""

from .base import FAMILY_TENNISBALL, Cell, Layout

__all__ = ["LAYOUT"]

LAYOUT = Layout(
    name="tennisball",
    family=FAMILY_TENNISBALL,
    description="tennisball 3N x 2N: two 270x90 degree bands, about +Y (top) and +X (bottom)",
    columns=1,
    rows=2,
    aspect=3,
    cells=(Cell(0, 0, 0), Cell(0, 1, 1)),
    face_names=("c1", "c2"),
)
