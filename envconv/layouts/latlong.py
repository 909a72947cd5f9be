"""latlong: the equirectangular map (OpenEXR ``envmap = latlong``, USD DomeLight ``latlong``).

::

    u=0          u=0.25        u=0.5         u=0.75        u=1
    +-------------------------------------------------------+  v=0    +Y (top row)
    |                                                       |
    |   -Z         +X            +Z            -X        -Z |  v=0.5  horizon
    |                                                       |
    +-------------------------------------------------------+  v=1    -Y (bottom row)
    <----------------------- 2N ---------------------------->   N rows

One cell, 2N × N. lon = 2π(0.5 − u), lat = π(0.5 − v),
d = (sin lon · cos lat, sin lat, cos lon · cos lat). Inverse: lon = atan2(x, z), lat = asin(y).
The whole cell is valid. Continued mapping (guard ring, filter taps): the same formulas past
their ranges, so columns wrap and rows past a pole continue on the opposite meridian.
"""

import math

from .._jit import jit
from .base import FAMILY_LATLONG, Cell, Layout

__all__ = ["LAYOUT", "face_to_dir", "dir_to_face", "density"]

LAYOUT = Layout(
    name="latlong",
    family=FAMILY_LATLONG,
    description="equirectangular 2N x N, +Z at the centre, +X at u=0.25 (OpenEXR/USD latlong)",
    columns=1,
    rows=1,
    aspect=2,
    cells=(Cell(0, 0, 0),),
    face_names=("latlong",),
)


@jit
def face_to_dir(face, a, b):
    """Direction of local point (a, b); u = (a + 1)/2, v = (b + 1)/2, continued past ±1."""
    lon = -math.pi * a
    lat = -0.5 * math.pi * b
    cl = math.cos(lat)
    return math.sin(lon) * cl, math.sin(lat), math.cos(lon) * cl


@jit
def dir_to_face(x, y, z):
    """(face, a, b) of a unit direction; a in [-1, 1] with -Z at a = -1."""
    lon = math.atan2(x, z)
    lat = math.asin(min(1.0, max(-1.0, y)))
    return 0, -lon / math.pi, -2.0 * lat / math.pi


@jit
def density(face, a, b):
    """Solid angle per unit area of (a, b): |cos lat| · π · π/2 (sr)."""
    return abs(math.cos(0.5 * math.pi * b)) * (0.5 * math.pi * math.pi)
