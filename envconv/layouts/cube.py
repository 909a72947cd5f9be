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

__all__ = ["FACE_NAMES"]

FACE_NAMES = ("px", "nx", "py", "ny", "pz", "nz")
