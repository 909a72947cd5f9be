"""The image formats envconv writes and reads by extension, and the pixel type each output gets.

No file is touched here: the tables the readers, the writers and the output plan (:mod:`envconv.io.encode`) share.
"""

from __future__ import annotations

import os
from typing import NamedTuple

from ..errors import UsageError

__all__ = ["COMPRESSIONS", "check_compression", "FORMATS", "CONTAINER_FORMATS", "WRITE_FORMATS", "extension",
           "format_of", "choose_pixel_type", "TextureInfo"]  # fmt: skip

#: Extension → (OIIO format, allowed pixel types, default for float sources, max channels).
FORMATS = {
    ".exr": ("openexr", ("half", "float"), None, None),
    ".hdr": ("hdr", ("float",), "float", 3),
    ".tif": ("tiff", ("uint8", "uint16", "half", "float"), None, None),
    ".tiff": ("tiff", ("uint8", "uint16", "half", "float"), None, None),
    ".png": ("png", ("uint8", "uint16"), "uint8", 4),
    ".jpg": ("jpeg", ("uint8",), "uint8", 3),
    ".jpeg": ("jpeg", ("uint8",), "uint8", 3),
    # Targa, as game skyboxes use it (Quake II/III, GoldSrc, Source): 8-bit RGB or RGBA,
    # uncompressed, rows stored bottom-up (origin bit clear), which every loader reads upright.
    ".tga": ("targa", ("uint8",), "uint8", 4),
}


#: Texture containers envconv writes and reads itself (:mod:`envconv.io.textures`), as above.
CONTAINER_FORMATS = {
    ".dds": ("dds", ("half", "float"), None, 4),
    ".ktx2": ("ktx2", ("half", "float"), None, 4),
}

#: Every format :func:`envconv.io.write` writes.
WRITE_FORMATS = {**FORMATS, **CONTAINER_FORMATS}


def extension(path: str | os.PathLike) -> str:
    """The extension of ``path``'s file name, lower-case, as pathlib's ``suffix`` finds it
    (``".exr"``; ``""`` for none, for a name ending in a dot, and for a hidden file's leading
    dot), without importing pathlib at every start."""
    name = os.path.basename(os.fspath(path))
    dot = name.rfind(".")
    return name[dot:].lower() if 0 < dot < len(name) - 1 else ""


def format_of(path: str):
    """The ``WRITE_FORMATS`` entry of ``path``'s extension; UsageError for an unknown one
    (an output path is an argument: exit 2 on the command line)."""
    ext = extension(path)
    if ext not in WRITE_FORMATS:
        known = " ".join(sorted(WRITE_FORMATS))
        raise UsageError(
            f"cannot write {path}: unknown extension {ext or '(none)'} (known: {known})"
        )
    return WRITE_FORMATS[ext]


def choose_pixel_type(path: str, pixel_type: str, bit_depth: str | None) -> str:
    """Pixel type written to ``path``: ``bit_depth``, else the source's if the format stores
    it, else the format's default for float sources (``FORMATS``), else half (from uint8) or
    float. Raises UsageError when the format cannot store ``bit_depth`` (a contradiction
    between two arguments)."""
    fmt, allowed, default, _ = format_of(path)
    if bit_depth is not None:
        if bit_depth not in allowed:
            raise UsageError(f"{fmt} cannot store {bit_depth}; it stores {', '.join(allowed)}")
        return bit_depth
    if pixel_type in allowed:
        return pixel_type
    if default is not None:
        return default
    return "half" if pixel_type == "uint8" else "float"


#: ``--compression`` choices per OIIO format; ``name:level`` is accepted where marked ``:``.
COMPRESSIONS = {
    "openexr": ("none", "rle", "zips:", "zip:", "piz", "pxr24", "b44", "b44a", "dwaa:", "dwab:",
                "htj2k32", "htj2k256"),
    "tiff": ("none", "lzw", "zip:", "packbits"),
}  # fmt: skip


def check_compression(fmt: str, compression: str | None) -> str | None:
    """Validate ``compression`` for OIIO format ``fmt``; return it lower-cased (None: default).

    Raises UsageError naming the choices (or saying the format takes none).
    """
    if compression is None:
        return None
    value = str(compression).strip().lower()
    choices = COMPRESSIONS.get(fmt)
    if not choices:
        raise UsageError(f"{fmt} output takes no --compression (only EXR and TIFF do)")
    name, _, level = value.partition(":")
    for choice in choices:
        if name == choice.rstrip(":") and (not level or (choice.endswith(":") and level.isdigit())):
            return value
    shown = ", ".join(c.rstrip(":") for c in choices)
    raise UsageError(f"unknown {fmt} compression {compression!r}; choose one of {shown} "
                     "(zip, zips, dwaa and dwab take a level, e.g. dwaa:45)")  # fmt: skip


class TextureInfo(NamedTuple):
    """What a DDS or KTX2 header says (:func:`envconv.io.dds.parse_dds`,
    :func:`envconv.io.ktx2.parse_ktx2`), enough to find every image without reading one.

    ``dtype`` is the stored component type (little-endian float16 or float32), ``components``
    3 or 4 (RGB or RGBA), ``opaque`` True when the alpha is a constant added for the format.
    ``images[(face, level)]`` is the byte offset of that image (``max(height >> k, 1)`` rows
    of ``max(width >> k, 1)`` texels, top row first after ``flip``, which is True for rows
    stored bottom first). ``metadata`` holds the file's key/value text (KTX2).
    """

    format: str
    width: int
    height: int
    levels: int
    cube: bool
    dtype: str
    components: int
    opaque: bool
    images: dict
    metadata: dict
    flip: bool = False
