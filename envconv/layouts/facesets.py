"""Game and engine skybox face sets: six files named and oriented as another program wants them.

A *face set* is the ``cube-faces`` layout (six N × N files through ``{face}`` in the path) with
another program's file names and each face's own turn or flip. Every face of every set below is
exactly one of envconv's cube faces (the GL/D3D/KTX table of :mod:`envconv.layouts.cube`, world
frame of docs/geometry.md) seen through a signed permutation of its local coordinates:

    file face pixel at (a, b)  =  envconv face ``slot`` at (a', b') = T · (a, b)

with (a, b) ∈ [-1, 1]², a to the right and b downward, and T one of the eight 2 × 2 signed
permutation matrices (turns by 90°, mirrors). Reading applies T to each file (so the map in
memory is envconv's own ``cube-faces`` map, and everything downstream works unchanged);
writing applies T⁻¹. Faces are square and T keeps their centre, so guard-grown faces and every
MIP level turn the same way. No resampling is involved: values are moved, never interpolated.

The tables come from each program's source or documentation (docs/conventions.md cites them).
Each program's world frame is taken to envconv's by the standard map of
:mod:`envconv.layouts.conventions` (Z-up right-handed: (x, y, z) → (x, z, −y); Unreal: → (−y, z, x)).

=============== ======================================= ====================================
set             files (in envconv slots px nx py ny pz nz)  faces
=============== ======================================= ====================================
``envconv``     px nx py ny pz nz                       the GL table itself
``quake``       lf rt up dn ft bk                       up is py turned 90° counter-clockwise,
                                                        dn is ny turned 90° clockwise
``unity-6sided`` left right up down front back          as is (Skybox/6 Sided)
``threejs``     px nx py ny pz nz                       as is (CubeTextureLoader, x flipped)
``godot``       x- x+ y+ y- z+ z-  (X+ holds world +X)  every face mirrored left-right
``unreal``      posy negy posz negz posx negx           posy turned 180°, negy as is, the
                                                        other four turned a quarter turn
=============== ======================================= ====================================

``quake`` is also Quake II/III (ioquake3), Half-Life (GoldSrc), Source and Cube 2: Sauerbraten,
whose sky code uses the same tables (aliases ``source``, ``cube2``, ``halflife`` …).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass

import numpy as np

from ..errors import LayoutError, UsageError

__all__ = [
    "FaceSet",
    "FACE_SETS",
    "get_face_set",
    "is_face_set",
    "to_envconv",
    "from_envconv",
    "face_to_file",
    "file_to_face",
]

_I = (1, 0, 0, 1)  # T as (t00, t01, t10, t11): a' = t00 a + t01 b, b' = t10 a + t11 b
_MIRROR = (-1, 0, 0, 1)  # a' = -a


@dataclass(frozen=True)
class FaceSet:
    """One program's six skybox files.

    Attributes
    ----------
    name : str
        Registry name (``--in-convention`` / ``--out-convention`` value).
    tool : str
        The programs that use it, one line.
    names : tuple of str
        File-name part for each of envconv's faces px nx py ny pz nz, in that order.
    transforms : tuple of 4-tuples
        For each envconv face k, T_k = (t00, t01, t10, t11): the file's pixel at (a, b) is
        envconv face k at (t00 a + t01 b, t10 a + t11 b).
    aliases : tuple of str
        Other names accepted for the set.
    file_order : tuple of str
        The program's own order of the files (for listings), default ``names``.
    """

    name: str
    tool: str
    names: tuple[str, ...]
    transforms: tuple[tuple[int, int, int, int], ...]
    aliases: tuple[str, ...] = ()
    file_order: tuple[str, ...] = ()

    @property
    def is_identity(self) -> bool:
        return all(t == _I for t in self.transforms)

    def order(self) -> tuple[str, ...]:
        """File names in the program's own order."""
        return self.file_order or self.names


_FACE_SET_LIST = (
    FaceSet(
        "envconv",
        "envconv's cube-faces: GL/D3D/KTX faces (also cmft, Unity and KTX cube arrays)",
        ("px", "nx", "py", "ny", "pz", "nz"),
        (_I,) * 6,
    ),
    FaceSet(
        "quake",
        "Quake II/III, ioquake3, Half-Life (GoldSrc), Source, Cube 2: Sauerbraten, DarkPlaces",
        ("lf", "rt", "up", "dn", "ft", "bk"),
        (_I, _I, (0, -1, 1, 0), (0, 1, -1, 0), _I, _I),
        aliases=(
            "source",
            "cube2",
            "halflife",
            "goldsrc",
            "quake2",
            "quake3",
            "ioquake3",
            "sauerbraten",
            "darkplaces",
        ),  # fmt: skip
        file_order=("rt", "bk", "lf", "ft", "up", "dn"),
    ),
    FaceSet(
        "unity-6sided",
        "Unity Skybox/6 Sided material: Front [+Z] Back [-Z] Left [+X] Right [-X] Up Down",
        ("left", "right", "up", "down", "front", "back"),
        (_I,) * 6,
        aliases=("unity6", "unity-6-sided"),
        file_order=("front", "back", "left", "right", "up", "down"),
    ),
    FaceSet(
        "threejs",
        "three.js CubeTextureLoader [px, nx, py, ny, pz, nz] (sampled with x negated)",
        ("px", "nx", "py", "ny", "pz", "nz"),
        (_I,) * 6,
        aliases=("three", "webgl"),
    ),
    FaceSet(
        "godot",
        "Godot Cubemap X+ X- Y+ Y- Z+ Z- sampled with Godot's world direction (Y up, -Z fwd)",
        ("x-", "x+", "y+", "y-", "z+", "z-"),
        (_MIRROR,) * 6,
        file_order=("x+", "x-", "y+", "y-", "z+", "z-"),
    ),
    FaceSet(
        "unreal",
        "Unreal TextureCube faces PosX..NegZ (D3D faces sampled with UE's Z-up LH world vector)",
        ("posy", "negy", "posz", "negz", "posx", "negx"),
        ((-1, 0, 0, -1), _I, (0, -1, 1, 0), (0, -1, 1, 0), (0, -1, 1, 0), (0, 1, -1, 0)),
        aliases=("ue", "ue4", "ue5"),
        file_order=("posx", "negx", "posy", "negy", "posz", "negz"),
    ),
)

#: Every face set by name, in documentation order.
FACE_SETS: dict[str, FaceSet] = {s.name: s for s in _FACE_SET_LIST}
_BY_NAME = {alias: s for s in _FACE_SET_LIST for alias in (s.name, *s.aliases)}


def is_face_set(name) -> bool:
    """Whether ``name`` (any case) names a face set or one of its aliases."""
    return isinstance(name, str) and name.strip().lower() in _BY_NAME


def get_face_set(name: str | FaceSet) -> FaceSet:
    """The face set called ``name`` (an alias or a FaceSet passes through); UsageError if none."""
    if isinstance(name, FaceSet):
        return name
    key = str(name).strip().lower()
    if key in _BY_NAME:
        return _BY_NAME[key]
    close = difflib.get_close_matches(key, list(_BY_NAME), n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise UsageError(f"unknown face set {name!r}{hint} (known: {', '.join(FACE_SETS)})")


def face_to_file(face: np.ndarray, transform) -> np.ndarray:
    """The file image of one envconv face image (H = W, any channels), by its T.

    file(a, b) = face(T (a, b)): a flip of the columns and/or rows, after a transpose when T
    swaps a and b. The result is a contiguous copy (or ``face`` itself for the identity).
    """
    if tuple(transform) == _I:
        return face
    _square(face)
    t00, t01, t10, t11 = transform
    if t01 == 0:  # a' = t00 a, b' = t11 b
        return np.ascontiguousarray(face[::t11, ::t00])
    swapped = face.swapaxes(0, 1)  # a' = t01 b, b' = t10 a
    return np.ascontiguousarray(swapped[::t01, ::t10])


def file_to_face(image: np.ndarray, transform) -> np.ndarray:
    """envconv's face image from one file image: the inverse of :func:`face_to_file`."""
    if tuple(transform) == _I:
        return image
    t00, t01, t10, t11 = transform
    return face_to_file(image, (t00, t10, t01, t11))  # T is orthogonal: T⁻¹ = Tᵀ


def _square(image: np.ndarray) -> int:
    height, width = image.shape[:2]
    if height != width:
        raise LayoutError(f"skybox faces must be square, got {width}x{height}")
    return height


def to_envconv(face_set: str | FaceSet, files: list[np.ndarray]) -> list[np.ndarray]:
    """envconv's six faces (px nx py ny pz nz) from a set's six file images in ``names`` order."""
    face_set = get_face_set(face_set)
    return [file_to_face(img, t) for img, t in zip(files, face_set.transforms, strict=True)]


def from_envconv(face_set: str | FaceSet, faces: list[np.ndarray]) -> list[np.ndarray]:
    """A set's six file images (in ``names`` order) from envconv's six faces."""
    face_set = get_face_set(face_set)
    return [face_to_file(img, t) for img, t in zip(faces, face_set.transforms, strict=True)]
