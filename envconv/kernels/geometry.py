"""Geometry dispatch on the integer family code, for use inside kernels.

Each function switches on ``family`` (``envconv.layouts.base.FAMILY_*``) and calls that layout
module's jitted map, so kernels stay generic and numba compiles one specialisation.
"""

from .._jit import jit
from ..layouts import angular, cube, cube_exr, latlong, paraboloid, sphere, tennisball
from ..layouts.base import (
    FAMILY_ANGULAR,
    FAMILY_CUBE_EXR,
    FAMILY_CUBE_GL,
    FAMILY_LATLONG,
    FAMILY_PARABOLOID,
    FAMILY_SPHERE,
)

__all__ = ["face_to_dir", "dir_to_face", "density", "is_disk"]


@jit
def face_to_dir(family, face, a, b):
    """Unit direction of local point (a, b) of ``face``, continued past the valid region."""
    if family == FAMILY_LATLONG:
        return latlong.face_to_dir(face, a, b)
    if family == FAMILY_CUBE_GL:
        return cube.face_to_dir(face, a, b)
    if family == FAMILY_CUBE_EXR:
        return cube_exr.face_to_dir(face, a, b)
    if family == FAMILY_SPHERE:
        return sphere.face_to_dir(face, a, b)
    if family == FAMILY_ANGULAR:
        return angular.face_to_dir(face, a, b)
    if family == FAMILY_PARABOLOID:
        return paraboloid.face_to_dir(face, a, b)
    return tennisball.face_to_dir(face, a, b)


@jit
def dir_to_face(family, x, y, z):
    """(face, a, b) of a unit direction, with (a, b) inside the face's valid region."""
    if family == FAMILY_LATLONG:
        return latlong.dir_to_face(x, y, z)
    if family == FAMILY_CUBE_GL:
        return cube.dir_to_face(x, y, z)
    if family == FAMILY_CUBE_EXR:
        return cube_exr.dir_to_face(x, y, z)
    if family == FAMILY_SPHERE:
        return sphere.dir_to_face(x, y, z)
    if family == FAMILY_ANGULAR:
        return angular.dir_to_face(x, y, z)
    if family == FAMILY_PARABOLOID:
        return paraboloid.dir_to_face(x, y, z)
    return tennisball.dir_to_face(x, y, z)


@jit
def density(family, face, a, b):
    """Solid angle per unit (a, b) area at (a, b) of ``face`` (sr)."""
    if family == FAMILY_LATLONG:
        return latlong.density(face, a, b)
    if family == FAMILY_CUBE_GL:
        return cube.density(face, a, b)
    if family == FAMILY_CUBE_EXR:
        return cube_exr.density(face, a, b)
    if family == FAMILY_SPHERE:
        return sphere.density(face, a, b)
    if family == FAMILY_ANGULAR:
        return angular.density(face, a, b)
    if family == FAMILY_PARABOLOID:
        return paraboloid.density(face, a, b)
    return tennisball.density(face, a, b)


@jit
def is_disk(family):
    """True for families whose valid region is the unit disk of each cell."""
    return family == FAMILY_SPHERE or family == FAMILY_ANGULAR or family == FAMILY_PARABOLOID
