"""Writing 8-bit pictures and viewer pages: the file side of :mod:`envconv.views.preview` and
:mod:`envconv.views.viewer`.

A picture is display-referred uint8 RGB, already tone-mapped; it is written as is, with no
colour conversion, to a temporary file that is then renamed into place.
"""

from __future__ import annotations

import os

import numpy as np

from .files import _oiio
from .output import write_bytes, write_files, write_images

__all__ = ["write_picture", "write_page"]


def write_picture(pixels: np.ndarray, path: str | os.PathLike) -> str:
    """Write ``pixels`` (H, W, 3 or 4) uint8 to ``path`` (PNG, JPEG, TIFF… by extension).

    The file is tagged ``oiio:ColorSpace = srgb_display`` (the preview's display encoding).
    Returns the path written. Raises :class:`~envconv.errors.ImageIOError` with a one-line
    message when the file cannot be written (:mod:`envconv.io.output` checks every result).
    """
    target = os.fspath(path)
    data = np.ascontiguousarray(pixels, dtype=np.uint8)
    spec = _oiio().ImageSpec(data.shape[1], data.shape[0], data.shape[2], "uint8")
    spec.attribute("oiio:ColorSpace", "srgb_display")
    write_files([target], lambda temp, _, __: write_images(temp, target, [(spec, "Create", data)]))
    return target


def write_page(text: str, path: str | os.PathLike) -> str:
    """Write ``text`` (an HTML page) as UTF-8 to ``path`` through a temporary file.

    Returns the path written; raises :class:`~envconv.errors.ImageIOError` on failure.
    """
    return write_bytes(text.encode("utf-8"), os.fspath(path))
