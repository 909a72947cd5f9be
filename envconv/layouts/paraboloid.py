"""paraboloid: dual paraboloid (Heidrich & Seidel), packed 2N × N as in the PowerVR paper.

::

    +----------------+----------------+
    |   .--------.   |   .--------.   |   left half:  front, z >= 0, (X, Y) = (x, y)/(1 + z)
    | /     +Y     \\ | /     +Y     \\ |   right half: back,  z <  0, (X, Y) = (x, y)/(1 - z)
    ||-X    +Z   +X |||+X    -Z   -X ||   u = (X + 1)/2, v = (1 - Y)/2 in each half
    | \\     -Y     / | \\     -Y     / |   valid where X² + Y² <= 1
    |   '--------'   |   '--------'   |
    +----------------+----------------+

Inverse (s = 1 + X² + Y²): front d = (2X, 2Y, 1 - X² - Y²)/s, back d = (2X, 2Y, -(1 - X² - Y²))/s.
The PowerVR lookup samples the packed image unchanged. Continued mapping: the same formula past
the circle. Solid angle per unit area: 4/s².
"""

from .base import FAMILY_PARABOLOID, Cell, Layout

__all__ = ["LAYOUT"]

LAYOUT = Layout(
    name="paraboloid",
    family=FAMILY_PARABOLOID,
    description="dual paraboloid packed 2N x N: front (z>=0) left, back right (PowerVR)",
    columns=2,
    rows=1,
    aspect=1,
    cells=(Cell(0, 0, 0), Cell(1, 0, 1)),
    face_names=("front", "back"),
)
