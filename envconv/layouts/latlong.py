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

from .base import FAMILY_LATLONG, Cell, Layout

__all__ = ["LAYOUT"]

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
