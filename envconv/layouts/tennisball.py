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

import math

from .._jit import jit
from .base import FAMILY_TENNISBALL, Cell, Layout

__all__ = ["LAYOUT", "face_to_dir", "dir_to_face", "density"]

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

_PHI_HALF = 0.75 * math.pi  # φ at a = -1
_THETA_HALF = 0.25 * math.pi  # θ at b = -1
_HALF_SQRT2 = 0.5 * math.sqrt(2.0)


@jit
def face_to_dir(face, a, b):
    """Direction of band point (a, b); u_c = (a + 1)/2, v_c = (b + 1)/2."""
    phi = -_PHI_HALF * a
    theta = -_THETA_HALF * b
    ct = math.cos(theta)
    if face == 0:
        return math.sin(phi) * ct, math.sin(theta), math.cos(phi) * ct
    return math.sin(theta), math.sin(phi) * ct, -math.cos(phi) * ct


@jit
def dir_to_face(x, y, z):
    """(face, a, b) of a direction, by the band rule."""
    if (z >= 0.0 and abs(y) <= _HALF_SQRT2) or (z <= 0.0 and abs(x) >= _HALF_SQRT2):
        theta = math.asin(min(1.0, max(-1.0, y)))
        phi = math.atan2(x, z)
        return 0, -phi / _PHI_HALF, -theta / _THETA_HALF
    theta = math.asin(min(1.0, max(-1.0, x)))
    phi = math.atan2(y, -z)
    return 1, -phi / _PHI_HALF, -theta / _THETA_HALF


@jit
def density(face, a, b):
    """Solid angle per unit (a, b) area: |cos θ| · (3π/4)(π/4) (sr)."""
    return abs(math.cos(_THETA_HALF * b)) * (_PHI_HALF * _THETA_HALF)
