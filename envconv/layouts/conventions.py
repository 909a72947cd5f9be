"""Conventions of other tools: ``--in-convention``, ``--out-convention``, ``--up`` and ``--axes``.

A file made by another tool is read as one of envconv's layouts (same image size, same cells),
and a *convention* says how that tool's pixels relate to envconv's geometry for the layout:

    w = M · d(p)                         (then, for some presets, a cell remap)

where d(p) is the unit direction envconv's own layout formula gives pixel p (docs/geometry.md),
w is the world direction (envconv's frame: right-handed, +Y up, +Z the lat-long centre) that
the tool stores at p, and M is an orthogonal 3×3 matrix, for the presets a signed permutation.
M may be improper (det −1): the tool's image is then a mirror image of envconv's.

Each tool's own frame is first taken to envconv's by the standard map for its kind:

    Y-up right-handed (OpenEXR, USD, skylibs)     (x, y, z)      unchanged
    Y-up left-handed, +Z forward (Unity, D3D)     (x, y, z)  ->  (−x, y, z)   (as glTFast does)
    Z-up right-handed (Blender)                   (x, y, z)  ->  (x, z, −y)   (glTF swizzle)
    Z-up left-handed, X fwd, Y right (Unreal)     (x, y, z)  ->  (−y, z, x)
    ffmpeg v360 (x right, y down, z front)        (x, y, z)  ->  (x, −y, −z)

so an image that looks unmirrored from inside in the tool also does in envconv. This is the
reading docs/geometry.md already uses for cube faces: the GL/D3D table is stated in the
left-handed frame c = (−x, y, z), which makes envconv's cube layouts *exactly* the cube files of
cmft, Unity, CubeMapGen and HDRShop. The relations, from conventions-in-the-wild.md:

=================  ================================  =====================  ========================
preset             layouts                           M (as AXES)            notes
=================  ================================  =====================  ========================
``envconv``        all                               ``x,y,z``              identity (also ``none``)
``openexr``        latlong, cube-exr                 ``x,y,z``              ImfEnvmap frame, USD
``openexr-edges``  latlong                           ``x,y,z`` + ``edges``  ImfEnvmap samples on
                                                     grid                   the edges (exrenvmap,
                                                                            maketx --envlatl)
``mitsuba``        latlong                           ``x,y,z`` + ``edge-    Mitsuba 3 ``envmap``:
                                                     rows`` grid            rows on the poles
``openexr``        cube-faces, cube-hstrip/vstrip    ``x,y,z`` + cell remap OpenEXR faces (exrenvmap
                                                                            ``%`` files): see below
``blender``        latlong                           ``z,y,-x``             centre +X_b, top +Z_b
``blender``        sphere                            ``x,y,z``              mirrorball = GL sphere
``cmft``           latlong, cube-vcross/hcross,      ``x,y,z``              LH, natural with G faces
                   cube-hstrip/vstrip, cube-faces
``skylibs``        latlong, cube-vcross              ``-x,y,-z``            centre −Z (yaw 180°)
``skylibs``        sphere, angular                   ``x,y,-z``             mirror image (s = +1)
``unity``          latlong                           ``-z,y,x``             Skybox/Panoramic
``unity``          cube-vcross/hcross/hstrip/vstrip, ``x,y,z``              6 Frames Layout, G faces
                   cube-faces
``unreal``         latlong                           ``z,y,-x``             long-lat cube import
``threejs``        latlong                           ``z,y,-x``             ``equirectUv``, flipY
``threejs``        cube-vcross/hcross/hstrip/vstrip, ``x,y,z``              CubeTexture px … nz,
                   cube-faces                                               ``flipEnvMap`` −1
``ffmpeg``         latlong (``e``), cube-hstrip      ``-x,y,-z``            default ``rludfb``, no
                   (``c6x1``), cube-vstrip (``c1x6``),                      face rotation; eac and
                   eac, fisheye                                             fisheye look at its
                                                                            front as envconv's at
                                                                            +Z: no preset needed
                                                                            with its own ``e``
``ffmpeg``         sphere (``ball``)                 ``x,y,-z``             mirror image (s = +1)
``probe-back``     sphere, angular                   ``x,y,z``              GL_SPHERE_MAP, Debevec,
                                                                            OIIO, Blender, USD
``probe-forward``  sphere, angular                   ``x,y,-z``             skylibs, ffmpeg ball
``pbrt``           equal-area                        ``-z,y,-x``            pbrt-v4 image infinite
                                                                            light; default N: the
                                                                            lat-long's width
``ddgi``           octahedral                        ``x,-z,y``             DDGI/RTXGI, Y-up RH
``ddgi-z-up``      octahedral                        ``x,y,z``              DDGI/RTXGI, Z-up RH
``unreal``         octahedral                        ``z,y,x``              RTXGI in Unreal
=================  ================================  =====================  ========================

A preset rejects every other layout with a one-line :class:`~envconv.errors.LayoutError`.
``mitsuba`` and ``openexr-edges`` also name a sample grid (:mod:`envconv.layouts.grids`): the
map is resampled onto envconv's pixel centres when read and onto the tool's grid when written.
Each preset also names its tool's world frame F (:func:`world_frame`, the map above: envconv's
direction = F · tool's direction), which ``envconv preview --convention`` labels views with.

three.js (``mrdoob/three.js``): ``equirectUv`` in ``src/renderers/shaders/ShaderChunk/common.glsl.js``
gives u = atan(d_z, d_x)/2π + 0.5, v = asin(d_y)/π + 0.5 with v = 1 the image's top row (the
default ``Texture.flipY = true``; ``examples/jsm/loaders/HDRLoader.js`` sets it too), so the
image centre is +X and u = 0.75 is +Z: w = (d_z, d_y, −d_x). Cube textures are sampled at
``vec3(flipEnvMap * reflectVec.x, reflectVec.yz)`` (``ShaderChunk/envmap_fragment.glsl.js``)
with ``flipEnvMap = -1`` for a ``CubeTexture`` that is not a render target
(``src/renderers/webgl/WebGLBackground.js``): the left-handed frame of envconv's own faces.

Octahedral squares: pbrt-v4 (``util/math.cpp``, ``cmd/imgtool.cpp``) reads a lat-long at
(atan2(y, x)/2π mod 1, acos(z)/π) for its direction e, which is envconv's w = (e_y, e_z, −e_x);
its square is envconv's equal-area transposed. ``imgtool makeequiarea`` makes the square as
wide as the lat-long, so with ``pbrt`` the default N is the width of the lat-long envconv
would make from the source. DDGI/RTXGI store world t at d = (t_x, t_z, −t_y).

AXES, a signed permutation written ``"-x,z,y"``, lists envconv's x, y and z in terms of the
tool's (file's) coordinates: ``"-x,z,y"`` means w = (−x_t, z_t, y_t). As a convention it is M
itself and applies to every layout. ``--axes`` and ``--up`` act on the environment between the
input and ``--rotate``: ``--axes AXES`` turns input-frame direction t into envconv's A·t, and
``--up z`` says the input world is Z-up right-handed; it is ``--axes x,z,-y`` (its +Z becomes
+Y, its +Y becomes −Z). ``--up y`` is the identity.

Cell remap of ``openexr`` on the GL-table layouts: OpenEXR's faces +X −X +Y −Y +Z −Z (family
E, each an unmirrored view in the right-handed world) sit in the six slots. Slot by slot, they
are envconv's faces −X_c +X_c +Y_c −Y_c +Z_c −Z_c, with ±Y turned 180°; so reading swaps the
first two slots and turns the ±Y faces, writing undoes it. M is the identity.

The resampler maps each output direction d to the source direction
``M_inᵀ · Aᵀ · Rᵀ · M_out · d`` (R the ``--rotate`` matrix, A from ``--axes``/``--up``).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field

import numpy as np

from ..errors import LayoutError, UsageError
from . import Layout, get_layout
from .grids import CENTRES

__all__ = [
    "Convention",
    "Preset",
    "PRESETS",
    "parse_axes",
    "resolve_convention",
    "environment_axes",
    "world_frame",
    "apply_remap",
]

_CUBE_GL = ("cube-vcross", "cube-hcross", "cube-hstrip", "cube-vstrip", "cube-faces")
_IDENTITY = "x,y,z"


@dataclass(frozen=True)
class Convention:
    """A resolved convention for one layout: the matrix M and an optional cell remap.

    Attributes
    ----------
    matrix : numpy.ndarray
        (3, 3) orthogonal M with w = M · d(p) (see module docstring).
    remap : tuple of (int, int) or None
        For each of envconv's faces k, ``(file_face, half_turns)``: envconv's face k is the
        file's face ``file_face`` turned by ``half_turns`` × 180°, both in their canonical
        orientation (cell rotations of the layout undone). None when cells are unchanged.
    name : str
        The preset name or AXES string it came from.
    size_rule : str or None
        How the tool sizes its files when no size is given: ``"latlong-width"`` (N is the
        width of the lat-long envconv would make from the source), or None for envconv's rule.
    grid : str
        Where the tool's lat-long samples sit (:data:`envconv.layouts.grids.GRIDS`):
        ``"centres"`` (envconv's pixel centres), ``"edge-rows"`` or ``"edges"``.
    """

    matrix: np.ndarray
    remap: tuple[tuple[int, int], ...] | None = None
    name: str = _IDENTITY
    size_rule: str | None = None
    grid: str = CENTRES

    @property
    def is_identity(self) -> bool:
        return (
            self.remap is None
            and self.grid == CENTRES
            and bool(np.array_equal(self.matrix, np.eye(3)))
        )


@dataclass(frozen=True)
class Preset:
    """A named convention: per-layout AXES strings, cell remaps, size rules and sample grids,
    and its tool."""

    name: str
    tool: str
    layouts: dict[str, str]
    remaps: dict[str, tuple[tuple[int, int], ...]] = field(default_factory=dict)
    sizes: dict[str, str] = field(default_factory=dict)
    #: Layout → sample grid other than envconv's centres (:mod:`envconv.layouts.grids`).
    grids: dict[str, str] = field(default_factory=dict)
    #: The tool's world frame as AXES: envconv's direction = F · (tool's direction).
    frame: str = "x,y,z"


# OpenEXR faces in the six slots of a GL-table layout → envconv's faces (module docstring).
_EXR_FACES = ((1, 0), (0, 0), (2, 1), (3, 1), (4, 0), (5, 0))

_PRESET_LIST = (
    Preset("envconv", "envconv itself: OpenEXR/USD frame, GL/D3D/KTX cube faces", {}),
    Preset(
        "openexr",
        "OpenEXR ImfEnvmap / exrenvmap frame, USD DomeLight, OIIO y-up (pixel centres)",
        {
            "latlong": _IDENTITY,
            "cube-exr": _IDENTITY,
            "cube-faces": _IDENTITY,
            "cube-hstrip": _IDENTITY,
            "cube-vstrip": _IDENTITY,
        },
        {"cube-faces": _EXR_FACES, "cube-hstrip": _EXR_FACES, "cube-vstrip": _EXR_FACES},
    ),  # fmt: skip
    Preset(
        "openexr-edges",
        "OpenEXR ImfEnvmap grid (exrenvmap, maketx --envlatl): samples on the image's edges",
        {"latlong": _IDENTITY},
        grids={"latlong": "edges"},
    ),
    Preset(
        "mitsuba",
        "Mitsuba 3 envmap emitter (Y-up RH): rows on the poles, columns at pixel centres",
        {"latlong": _IDENTITY},
        grids={"latlong": "edge-rows"},
    ),
    Preset(
        "blender",
        "Blender Cycles Environment Texture (Z-up RH): equirectangular and mirror ball",
        {"latlong": "z,y,-x", "sphere": _IDENTITY},
        frame="x,z,-y",
    ),
    Preset(
        "cmft",
        "cmft / Filament cmgen (Y-up, left-handed like D3D): latlong and G-face cubes",
        {"latlong": _IDENTITY, **dict.fromkeys(_CUBE_GL, _IDENTITY)},
        frame="-x,y,z",
    ),
    Preset(
        "skylibs",
        "skylibs (Y-up RH, -Z forward): latlong, cube cross (E faces), sphere, angular",
        {"latlong": "-x,y,-z", "cube-vcross": "-x,y,-z", "sphere": "x,y,-z", "angular": "x,y,-z"},
    ),
    Preset(
        "unity",
        "Unity Skybox/Panoramic (Y-up LH, +Z forward): latlong and 6 Frames Layout",
        {"latlong": "-z,y,x", **dict.fromkeys(_CUBE_GL, _IDENTITY)},
        frame="-x,y,z",
    ),
    Preset(
        "unreal",
        "Unreal (Z-up LH, X forward, Y right): long-lat cubemap import; RTXGI octahedral probes",
        {"latlong": "z,y,-x", "octahedral": "z,y,x"},
        frame="-y,z,x",
    ),
    Preset(
        "threejs",
        "three.js (Y-up RH): equirectangular textures (equirectUv, flipY) and CubeTexture faces",
        {"latlong": "z,y,-x", **dict.fromkeys(_CUBE_GL, _IDENTITY)},
    ),
    Preset(
        "ffmpeg",
        "ffmpeg v360 (x right, y down, z front): e, c6x1, c1x6 (rludfb, no rotation), eac, "
        "fisheye, ball",
        {
            "latlong": "-x,y,-z",
            "cube-hstrip": "-x,y,-z",
            "cube-vstrip": "-x,y,-z",
            "eac": "-x,y,-z",
            "fisheye": "-x,y,-z",
            "sphere": "x,y,-z",
        },
        frame="x,-y,-z",
    ),  # fmt: skip
    Preset(
        "probe-back",
        "mirror-ball/angular probes whose centre is +Z, toward the camera (GL, Debevec, OIIO)",
        {"sphere": _IDENTITY, "angular": _IDENTITY},
    ),
    Preset(
        "probe-forward",
        "mirror-ball/angular maps whose centre is forward -Z, unmirrored (skylibs, ffmpeg ball)",
        {"sphere": "x,y,-z", "angular": "x,y,-z"},
    ),
    Preset(
        "pbrt",
        "pbrt-v4 image infinite light: the equal-area square of imgtool makeequiarea",
        {"equal-area": "-z,y,-x"},
        sizes={"equal-area": "latlong-width"},
        frame="y,z,-x",
    ),
    Preset(
        "ddgi",
        "DDGI/RTXGI octahedral probes (+Z centre) in a Y-up right-handed world",
        {"octahedral": "x,-z,y"},
    ),
    Preset(
        "ddgi-z-up",
        "DDGI/RTXGI octahedral probes (+Z centre) in a Z-up right-handed world",
        {"octahedral": _IDENTITY},
        frame="x,z,-y",
    ),
)

#: Every preset by name.
PRESETS: dict[str, Preset] = {p.name: p for p in _PRESET_LIST}
_ALIASES = {
    "none": "envconv", "identity": "envconv", "usd": "openexr", "filament": "cmft",
    "pbrt-v4": "pbrt", "rtxgi": "ddgi", "rtxgi-z-up": "ddgi-z-up", "three.js": "threejs",
    "three": "threejs", "mitsuba3": "mitsuba", "exrenvmap": "openexr-edges",
    "maketx": "openexr-edges",
}  # fmt: skip


def parse_axes(spec: str) -> np.ndarray:
    """Signed permutation matrix A of an AXES string such as ``"-x,z,y"``.

    Row i of A holds envconv's i-th component in terms of the tool's (x, y, z): ``"-x,z,y"``
    gives w = (−t_x, t_z, t_y).

    Examples
    --------
    >>> parse_axes("-x,z,y") @ [1.0, 2.0, 3.0]
    array([-1.,  3.,  2.])
    """
    parts = [p.strip().lower() for p in str(spec).replace(" ", "").split(",")]
    matrix = np.zeros((3, 3))
    used = set()
    bad = UsageError(
        f"axes must list x, y and z once each, optionally signed, e.g. '-x,z,y'; got {spec!r}"
    )
    if len(parts) != 3:
        raise bad
    for row, part in enumerate(parts):
        sign = -1.0 if part.startswith("-") else 1.0
        letter = part.lstrip("+-")
        if len(part) - len(letter) > 1 or letter not in ("x", "y", "z") or letter in used:
            raise bad
        used.add(letter)
        matrix[row, "xyz".index(letter)] = sign
    return matrix


def _check_matrix(matrix) -> np.ndarray:
    matrix = np.asarray(matrix, np.float64)
    if matrix.shape != (3, 3) or not np.all(np.isfinite(matrix)):
        raise UsageError(f"a convention matrix must be 3x3 and finite, got shape {matrix.shape}")
    if not np.allclose(matrix @ matrix.T, np.eye(3), atol=1e-9):
        raise UsageError("a convention matrix must be orthogonal (a rotation or a mirror)")
    return matrix


def _preset_name(spec: str) -> str:
    name = _ALIASES.get(spec.strip().lower(), spec.strip().lower())
    if name not in PRESETS:
        close = difflib.get_close_matches(name, list(PRESETS) + list(_ALIASES), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise UsageError(f"unknown convention {spec!r}{hint} (presets: {', '.join(PRESETS)}; "
                         "or an axis remap such as -x,z,y)")  # fmt: skip
    return name


def resolve_convention(spec, layout: Layout | str) -> Convention:
    """Resolve a convention spec for ``layout``.

    Parameters
    ----------
    spec : None, str, array_like or Convention
        A preset name (see :data:`PRESETS`), an AXES string (``"-x,z,y"``), a 3×3 orthogonal
        matrix M, or a Convention. None, ``"envconv"`` and ``"none"`` are the identity.
    layout : str or Layout
        The layout of the file the convention describes.

    Returns
    -------
    Convention

    Raises
    ------
    LayoutError
        The preset does not apply to ``layout`` (message names the layouts it applies to).
    UsageError
        Unknown name, malformed AXES or a matrix that is not orthogonal.
    """
    layout = get_layout(layout)
    if isinstance(spec, Convention):
        return spec
    if spec is None:
        return Convention(np.eye(3), None, "envconv")
    if not isinstance(spec, str):
        return Convention(_check_matrix(spec), None, "matrix")
    text = spec.strip()
    if "," in text:
        return Convention(parse_axes(text), None, text)
    name = _preset_name(spec)
    preset = PRESETS[name]
    if name == "envconv":
        return Convention(np.eye(3), None, name)
    if layout.name not in preset.layouts:
        raise LayoutError(
            f"convention {name} applies to {', '.join(preset.layouts)}, not {layout.name}"
        )
    return Convention(
        parse_axes(preset.layouts[layout.name]),
        preset.remaps.get(layout.name),
        name,
        preset.sizes.get(layout.name),
        preset.grids.get(layout.name, CENTRES),
    )


def environment_axes(up: str | None = None, axes: str | None = None) -> np.ndarray:
    """Matrix A of ``--up`` / ``--axes``: input-frame direction t becomes envconv's A · t.

    ``up="z"`` is ``axes="x,z,-y"`` (a Z-up right-handed input: +Z becomes +Y); ``up="y"`` or
    None is the identity. Giving both is an error.
    """
    if up not in (None, "y", "z", "Y", "Z"):
        raise UsageError(f"up must be 'y' or 'z', got {up!r}")
    if axes is not None and up is not None and str(up).lower() == "z":
        raise UsageError("pass either --up z or --axes, not both")
    if axes is not None:
        return parse_axes(axes)
    if up is not None and str(up).lower() == "z":
        return parse_axes("x,z,-y")
    return np.eye(3)


def world_frame(spec) -> tuple[np.ndarray, str]:
    """(F, name) of a tool's world frame: envconv's direction = F · the tool's direction.

    ``spec`` is a preset name (its :attr:`Preset.frame`), an AXES string (F itself, as for
    ``--axes``) or None (envconv's frame, the identity).
    """
    if spec is None:
        return np.eye(3), "envconv"
    text = str(spec).strip()
    if "," in text:
        return parse_axes(text), text
    name = _preset_name(text)
    return parse_axes(PRESETS[name].frame), name


def _cell_blocks(layout: Layout, pixels: np.ndarray, guard: int):
    """(face → (row slice, col slice, cell turns)) for the grown cells of a mosaic."""
    n = layout.size_from_image(pixels.shape[1], pixels.shape[0], guard)
    cw, ch = layout.cell_size(n, guard)
    return {
        cell.face: (slice(cell.row * ch, (cell.row + 1) * ch),
                    slice(cell.col * cw, (cell.col + 1) * cw), cell.turns)
        for cell in layout.cells
    }  # fmt: skip


def apply_remap(layout: Layout | str, pixels: np.ndarray, guard: int, remap, inverse=False):
    """Permute and turn the cells of a mosaic by a convention's cell remap.

    Parameters
    ----------
    layout : str or Layout
        Layout of ``pixels`` (H, W, C); cells are grown by ``guard`` pixels.
    remap : tuple of (file_face, half_turns)
        See :attr:`Convention.remap`. Forward (``inverse=False``) turns a tool's file into
        envconv's layout; ``inverse=True`` turns envconv's layout into the tool's file.

    Returns
    -------
    numpy.ndarray
        A new array; pixels outside cells are copied unchanged.
    """
    layout = get_layout(layout)
    if remap is None:
        return pixels
    blocks = _cell_blocks(layout, pixels, guard)
    faces = {}
    for face, (rows, cols, turns) in blocks.items():
        faces[face] = np.rot90(pixels[rows, cols], k=-turns)  # canonical orientation
    out = pixels.copy()
    for ours, (theirs, half_turns) in enumerate(remap):
        if inverse:
            dest, image = theirs, np.rot90(faces[ours], k=-2 * half_turns)
        else:
            dest, image = ours, np.rot90(faces[theirs], k=2 * half_turns)
        rows, cols, turns = blocks[dest]
        out[rows, cols] = np.rot90(image, k=turns)
    return out
