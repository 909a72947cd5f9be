"""What writing a map will store, decided before a pixel exists: the writer's own rules.

:func:`envconv.io.write` applies these rules as it writes, and every plan asks them first
(the engine's plan of a run, :func:`envconv.engine.api.plan_convert`, a dry run), so what a
plan promises and what a write does cannot drift apart:

* :func:`output_paths`: the files a write makes of a path (``{face}``, ``{level}``);
* :func:`check_write`: whether a file can hold what is asked (MIP levels, a texture
  container's cube), from names and counts alone: UsageError (exit 2) when two arguments
  contradict each other, e.g. ``--mips`` to a PNG without ``{level}`` in its path;
* :func:`stored_channels`: the channels a format keeps of a map's channels;
* :func:`container_levels`: how many levels of a chain a DDS or KTX2 cube map holds;
* :func:`plan_write`: all of it for one write: files, format, pixel type, compression, the
  colour space written, channels and levels (:class:`WritePlan`).

Nothing here opens a file.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from ..errors import LayoutError, UsageError
from ..layouts import Layout, get_layout
from .face_files import fill_placeholder, has_placeholder, literal_path
from .formats import CONTAINER_FORMATS, format_of

__all__ = ["WritePlan", "output_paths", "face_names", "check_write", "stored_channels",
           "container_levels", "plan_write", "ONE_IMAGE_HINT"]  # fmt: skip

#: How to write a chain to a format that holds one image.
ONE_IMAGE_HINT = "put {level} in the path for one file per level, e.g. sky_{level}.png"


@dataclass(frozen=True)
class WritePlan:
    """What one write stores.

    Attributes
    ----------
    files : tuple of str
        Every file written, in the order the writer writes them.
    format : str
        OpenImageIO's name of the format (``openexr``, ``png``, …; ``dds``, ``ktx2``).
    pixel_type : str
        ``half``, ``float``, ``uint8`` or ``uint16``, as stored.
    compression : str or None
        The compression asked for (None: the format's default).
    colorspace : str
        OpenColorIO name of the colour space the pixels are written in.
    channels : tuple of str
        The channels each file holds.
    levels : int
        MIP levels each file holds (1 for one file per level with ``{level}``).
    """

    files: tuple[str, ...]
    format: str
    pixel_type: str
    compression: str | None
    colorspace: str
    channels: tuple[str, ...]
    levels: int


def output_paths(envmap_layout, path: str | os.PathLike, levels: int = 1, faces=None) -> list[str]:
    """Files that writing a map of this layout to ``path`` produces.

    With ``{level}`` in the path every one of ``levels`` mip levels is a file of its own
    (``{level}`` becomes 0, 1, …); multi-file layouts combine it with ``{face}``, in a file
    name or a folder name. ``faces`` names the files of a ``cube-faces`` map by a face set
    (:mod:`envconv.layouts.facesets`). A DDS or KTX2 file holds every face and level itself.
    Doubled braces stand for one (``a{{level}}.exr`` is the file ``a{level}.exr``;
    :func:`envconv.io.face_files.escape_braces`).
    """
    return [literal_path(p) for p in _placed_paths(envmap_layout, os.fspath(path), levels, faces)]


def _placed_paths(envmap_layout, path: str, levels: int, faces) -> list[str]:
    """:func:`output_paths` before the doubled braces are undone."""
    if os.path.splitext(path)[1].lower() in CONTAINER_FORMATS:
        if has_placeholder(path, "level") or has_placeholder(path, "face"):
            raise LayoutError(f"{path}: a DDS or KTX2 file holds every face and level; "
                              "drop {face} and {level} from the path")  # fmt: skip
        return [path]
    if has_placeholder(path, "level"):
        return [p for k in range(max(int(levels), 1))
                for p in _placed_paths(envmap_layout, fill_placeholder(path, "level", str(k)), 1,
                                       faces)]  # fmt: skip
    layout = get_layout(envmap_layout)
    names = face_names(layout, faces)
    if layout.multi_file:
        if not has_placeholder(path, "face"):
            raise LayoutError(
                f"layout {layout.name} writes {len(layout.face_names)} files; "
                "put {face} in the output path, e.g. sky_{face}.exr"
            )
        return [fill_placeholder(path, "face", name) for name in names]
    if has_placeholder(path, "face"):
        raise LayoutError(
            f"{{face}} in the output path needs a multi-file layout, not {layout.name}"
        )
    return [path]


def face_names(layout, faces=None) -> tuple[str, ...]:
    """File-name parts of a layout's faces, or of a face set's files (cube-faces only)."""
    if faces is None:
        return layout.face_names
    from ..layouts.facesets import get_face_set

    face_set = get_face_set(faces)
    if layout.name != "cube-faces":
        raise LayoutError(f"face set {face_set.name} applies to cube-faces, not {layout.name}")
    return face_set.names


def check_write(layout: Layout | str, path: str, levels: int | bool = 1,
                full: int | None = None, guard: int = 0) -> None:  # fmt: skip
    """Refuse, with a UsageError naming both sides, a write that ``path`` cannot hold.

    ``levels`` is the number of MIP levels to write, or True for a full chain whose length is
    not known yet (no size); ``full`` is the length of the full chain when it is known.
    Refused: a chain in a format that holds one image (PNG, JPEG, HDR) without ``{level}``;
    an OpenEXR chain that is not the full one (OpenEXR's MIPMAP_LEVELS holds every level down
    to 1 x 1); a DDS or KTX2 file of a guarded cube layout or of a multi-file layout.
    """
    path = os.fspath(path)
    layout = get_layout(layout)
    fmt = format_of(path)[0]
    if os.path.splitext(path)[1].lower() in CONTAINER_FORMATS:
        _check_container(layout, guard, path)
        return
    chain = levels is True or int(levels) > 1
    if not chain or has_placeholder(path, "level"):
        return
    count = "a MIP chain" if levels is True else f"{int(levels)} MIP levels"
    if fmt not in ("openexr", "tiff"):
        raise UsageError(f"cannot write {path}: {fmt} holds one image, not {count}; "
                         f"{ONE_IMAGE_HINT}")  # fmt: skip
    if fmt == "openexr" and levels is not True and full is not None and int(levels) != full:
        raise UsageError(f"cannot write {path}: a MIP-mapped OpenEXR holds all {full} levels "
                         f"down to 1x1, not {int(levels)}; ask for the full chain (--mips) or "
                         "put {level} in the path")  # fmt: skip


def _check_container(layout: Layout, guard: int, path: str) -> None:
    from ..layouts.base import FAMILY_CUBE_GL

    if layout.family == FAMILY_CUBE_GL and guard:
        raise UsageError(f"cannot write {path}: DDS and KTX2 cube maps have no guard ring; "
                         f"write {layout.name} without --guard")  # fmt: skip
    if layout.family != FAMILY_CUBE_GL and layout.multi_file:
        raise UsageError(f"cannot write {path}: DDS and KTX2 hold one image or one cube, not "
                         f"{layout.name}'s files")  # fmt: skip


def stored_channels(path: str, channels) -> tuple[str, ...]:
    """The channels a file at ``path`` holds of a map with ``channels``: all of them, or the
    first the format stores (PNG 4, JPEG 3), RGB for Radiance HDR (one channel is repeated),
    RGBA for DDS and KTX2 (a missing alpha stored as 1)."""
    fmt, _, _, max_channels = format_of(os.fspath(path))
    channels = tuple(channels)
    if fmt in ("dds", "ktx2"):
        return ("R", "G", "B", "A")
    if max_channels is not None and len(channels) > max_channels:
        channels = channels[:max_channels]
    if fmt == "hdr" and len(channels) != 3:
        channels = ("R", "G", "B")
    return channels


def container_levels(layout: Layout | str, n: int, levels: int) -> int:
    """How many of a chain's ``levels`` a DDS or KTX2 file of ``layout`` with faces of ``n``
    texels holds: every level for a 2-D texture; for a cube map, the leading levels whose
    cells are whole faces of ``max(n >> k, 1)`` texels (a cross or strip chain goes on below
    1-texel faces, and n not a power of two cuts lower levels' faces into fractions)."""
    from ..layouts.base import FAMILY_CUBE_GL

    layout = get_layout(layout)
    if layout.family != FAMILY_CUBE_GL:
        return levels
    width, height = layout.columns * n, layout.rows * n
    kept = 0
    for k in range(levels):
        side = max(n >> k, 1)
        whole = (max(height >> k, 1), max(width >> k, 1)) == (layout.rows * side,
                                                              layout.columns * side)  # fmt: skip
        if not whole or (k and n >> k == 0):
            break
        kept += 1
    return kept


def plan_write(layout: Layout | str, path: str, size: int, guard: int = 0, levels: int = 1,
               channels=("R", "G", "B"), pixel_type: str = "float", metadata=None, faces=None,
               bit_depth=None, compression=None, output_colorspace=None, ocio_config=None,
               **_ignored) -> WritePlan:  # fmt: skip
    """The :class:`WritePlan` of writing a map (layout, N = ``size``, guard, ``levels`` MIP
    levels, ``channels``, ``pixel_type``, ``metadata`` with its ``oiio:ColorSpace``) to
    ``path`` with :func:`envconv.io.write`'s options; UsageError as :func:`check_write` and
    for a bit depth, compression or colour space the format or config does not know.
    Other keywords of ``write`` (``dither``) change no fact planned here."""
    from ..resample.mips import full_level_count
    from .encode import plan_output

    layout = get_layout(layout)
    path = os.fspath(path)
    full = full_level_count(*layout.file_size(size, guard))
    check_write(layout, path, levels, full, guard)
    per_level = has_placeholder(path, "level")
    files = output_paths(layout, path, levels if per_level else 1, faces=faces)
    output = plan_output(path, pixel_type, dict(metadata or {}), output_colorspace, bit_depth,
                         ocio_config, compression)  # fmt: skip
    if per_level:
        stored = 1
    elif output.format in ("dds", "ktx2"):
        stored = container_levels(layout, size, levels)
    else:
        stored = levels
    return WritePlan(tuple(files), output.format, output.pixel_type, output.compression,
                     output.colorspace, stored_channels(path, channels), stored)  # fmt: skip
