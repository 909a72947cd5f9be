"""Cube-face geometry shared by the cross, strip and six-file layouts (the GL/D3D/KTX table).

Faces are stored as OpenGL, Direct3D and KTX index a cube map, in the left-handed cube frame
c = (−x, y, z): +Z_c is the lat-long centre and +X_c is on the viewer's right. Each face is an
unmirrored view from inside the cube. Face order: +X_c, −X_c, +Y_c, −Y_c, +Z_c, −Z_c
(file suffixes px nx py ny pz nz). Face texel (a, b), a right and b down:

    face    c before normalising
    +X_c    ( 1, -b, -a)
    -X_c    (-1, -b,  a)
    +Y_c    ( a,  1,  b)
    -Y_c    ( a, -1, -b)
    +Z_c    ( a, -b,  1)
    -Z_c    (-a, -b, -1)

The world direction is d = normalise(−c_x, c_y, c_z). Direction → face picks the major axis;
exact ties go to x, then y, then z, and a zero component counts as positive. The continued
mapping (guard rings, filter taps past an edge) is the face plane extended past ±1.
"""

import math

from .._jit import jit

__all__ = ["FACE_NAMES", "face_to_dir", "dir_to_face", "density"]

FACE_NAMES = ("px", "nx", "py", "ny", "pz", "nz")


@jit
def face_to_dir(face, a, b):
    """Unit world direction of point (a, b) on ``face`` (0..5, GL order)."""
    if face == 0:
        x, y, z = -1.0, -b, -a
    elif face == 1:
        x, y, z = 1.0, -b, a
    elif face == 2:
        x, y, z = -a, 1.0, b
    elif face == 3:
        x, y, z = -a, -1.0, -b
    elif face == 4:
        x, y, z = -a, -b, 1.0
    else:
        x, y, z = a, -b, -1.0
    inv = 1.0 / math.sqrt(x * x + y * y + z * z)
    return x * inv, y * inv, z * inv


@jit
def dir_to_face(x, y, z):
    """(face, a, b) of a direction, with a, b in [-1, 1]."""
    cx = -x
    ax, ay, az = abs(cx), abs(y), abs(z)
    if ax >= ay and ax >= az:
        if cx >= 0.0:
            return 0, -z / ax, -y / ax
        return 1, z / ax, -y / ax
    if ay >= az:
        if y >= 0.0:
            return 2, cx / ay, z / ay
        return 3, cx / ay, -z / ay
    if z >= 0.0:
        return 4, cx / az, -y / az
    return 5, -cx / az, -y / az


@jit
def density(face, a, b):
    """Solid angle per unit area of (a, b) on a face: (1 + a² + b²)^(-3/2) (sr)."""
    r2 = 1.0 + a * a + b * b
    return 1.0 / (r2 * math.sqrt(r2))
