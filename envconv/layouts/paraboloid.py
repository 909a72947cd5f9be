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

from .._jit import jit
from .base import FAMILY_PARABOLOID, Cell, Layout

__all__ = ["LAYOUT", "face_to_dir", "dir_to_face", "density"]

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


@jit
def face_to_dir(face, a, b):
    """Direction of point (a, b) = (X, -Y) of the front (0) or back (1) half."""
    X, Y = a, -b
    r2 = X * X + Y * Y
    s = 1.0 / (1.0 + r2)
    z = (1.0 - r2) * s
    if face == 1:
        z = -z
    return 2.0 * X * s, 2.0 * Y * s, z


@jit
def dir_to_face(x, y, z):
    """(face, a, b) of a direction: front for z >= 0, back for z < 0."""
    if z >= 0.0:
        k = 1.0 / (1.0 + z)
        return 0, x * k, -y * k
    k = 1.0 / (1.0 - z)
    return 1, x * k, -y * k


@jit
def density(face, a, b):
    """Solid angle per unit (a, b) area: 4 / (1 + X² + Y²)² (sr)."""
    s = 1.0 + a * a + b * b
    return 4.0 / (s * s)
