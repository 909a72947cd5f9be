"""The image formats envconv writes and reads by extension, and the pixel type each output gets.

No file is touched here: this is the table :mod:`envconv.io` and :mod:`envconv.colorflow` share.
"""

from __future__ import annotations

from pathlib import Path

from .errors import ImageIOError

__all__ = ["FORMATS", "CONTAINER_FORMATS", "WRITE_FORMATS", "format_of", "choose_pixel_type"]

#: Extension → (OIIO format, allowed pixel types, default for float sources, max channels).
FORMATS = {
    ".exr": ("openexr", ("half", "float"), None, None),
    ".hdr": ("hdr", ("float",), "float", 3),
    ".tif": ("tiff", ("uint8", "uint16", "half", "float"), None, None),
    ".tiff": ("tiff", ("uint8", "uint16", "half", "float"), None, None),
    ".png": ("png", ("uint8", "uint16"), "uint8", 4),
    ".jpg": ("jpeg", ("uint8",), "uint8", 3),
    ".jpeg": ("jpeg", ("uint8",), "uint8", 3),
}


#: Texture containers envconv writes itself, never reads (:mod:`envconv.textures`), as above.
CONTAINER_FORMATS = {
    ".dds": ("dds", ("half", "float"), None, 4),
    ".ktx2": ("ktx2", ("half", "float"), None, 4),
}

#: Every format :func:`envconv.io.write` writes.
WRITE_FORMATS = {**FORMATS, **CONTAINER_FORMATS}


def format_of(path: str):
    """The ``WRITE_FORMATS`` entry of ``path``'s extension; ImageIOError for an unknown one."""
    ext = Path(path).suffix.lower()
    if ext not in WRITE_FORMATS:
        known = " ".join(sorted(WRITE_FORMATS))
        raise ImageIOError(
            f"cannot write {path}: unknown extension {ext or '(none)'} (known: {known})"
        )
    return WRITE_FORMATS[ext]


def choose_pixel_type(path: str, pixel_type: str, bit_depth: str | None) -> str:
    """Pixel type written to ``path``: ``bit_depth``, else the source's if the format stores
    it, else the format's default for float sources (``FORMATS``), else half (from uint8) or
    float. Raises ImageIOError when the format cannot store ``bit_depth``."""
    fmt, allowed, default, _ = format_of(path)
    if bit_depth is not None:
        if bit_depth not in allowed:
            raise ImageIOError(f"{fmt} cannot store {bit_depth}; it stores {', '.join(allowed)}")
        return bit_depth
    if pixel_type in allowed:
        return pixel_type
    if default is not None:
        return default
    return "half" if pixel_type == "uint8" else "float"
