"""Writing 8-bit pictures and viewer pages: the file side of :mod:`envconv.views.preview` and
:mod:`envconv.views.viewer`.

A picture is display-referred uint8 RGB, already tone-mapped; it is written as is, with no
colour conversion, to a temporary file that is then renamed into place.
"""

from __future__ import annotations

import os

import numpy as np

from ..errors import ImageIOError
from .chatter import library_output
from .files import _first_line, _oiio
from .temps import discard, temp_for
from .writer import write_bytes

__all__ = ["write_picture", "write_page"]


def write_picture(pixels: np.ndarray, path: str | os.PathLike) -> str:
    """Write ``pixels`` (H, W, 3 or 4) uint8 to ``path`` (PNG, JPEG, TIFF… by extension).

    The file is tagged ``oiio:ColorSpace = srgb_display`` (the preview's display encoding).
    Returns the path written. Raises :class:`~envconv.errors.ImageIOError` with a one-line
    message when the file cannot be written.
    """
    target = os.fspath(path)
    data = np.ascontiguousarray(pixels, dtype=np.uint8)
    oiio = _oiio()
    out = oiio.ImageOutput.create(target)
    if out is None:
        raise ImageIOError(f"cannot write {target}: {_first_line(oiio.geterror())}")
    temp = temp_for(target)
    spec = oiio.ImageSpec(data.shape[1], data.shape[0], data.shape[2], "uint8")
    spec.attribute("oiio:ColorSpace", "srgb_display")
    try:
        with library_output(f"cannot write {target}", temp):  # what libpng/libjpeg print
            ok = out.open(temp, spec) and out.write_image(data)
            message = out.geterror()
            ok = out.close() and ok
            del out
        if not ok:
            raise ImageIOError(f"cannot write {target}: {_first_line(message)}")
        os.replace(temp, target)
    finally:
        discard(temp)
    return target


def write_page(text: str, path: str | os.PathLike) -> str:
    """Write ``text`` (an HTML page) as UTF-8 to ``path`` through a temporary file.

    Returns the path written; raises :class:`~envconv.errors.ImageIOError` on failure.
    """
    return write_bytes(text.encode("utf-8"), os.fspath(path))
