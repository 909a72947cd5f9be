"""One image file to and from float32 pixels and its header, through OpenImageIO and OpenEXR.

This module knows files, not layouts: :mod:`envconv.io` builds environment maps on top of it.
OpenImageIO opens every file and reads every header; the pixels of plain scanline EXRs are
decoded by the OpenEXR library, which is faster at it (:mod:`envconv.exr_io`).
"""

from __future__ import annotations

import os
import re
from contextlib import contextmanager
from typing import Any

import numpy as np

from .errors import ImageIOError
from .exr_io import is_plain_exr as _plain_exr
from .exr_io import read_exr_pixels as _read_exr_pixels
from .formats import FORMATS

__all__ = ["read_image", "read_header", "read_pixel_type", "FORMATS"]

def _oiio():
    import OpenImageIO

    return OpenImageIO


def read_image(path: str | os.PathLike, level: int = 0):
    """Read one image file as float32 (H, W, C).

    Returns
    -------
    pixels, channel names, metadata dict, pixel type (``half``/``float``/``uint8``/``uint16``)
    """
    return _decode(os.fspath(path), level)


def _decode(path: str, level: int):
    if not os.path.exists(path):
        raise ImageIOError(f"input file not found: {path}")
    if os.path.isdir(path):
        raise ImageIOError(f"input is a directory, not an image: {path}")
    oiio = _oiio()
    # Alpha is a validity mask, never a compositing alpha: read colour exactly as stored, so
    # OIIO does not premultiply unassociated alpha (PNG, TIFF) on the way in.
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)
    inp = oiio.ImageInput.open(path, config)
    if inp is None:
        raise ImageIOError(f"cannot read {path}: {_first_line(oiio.geterror())}")
    try:
        if level and not inp.seek_subimage(0, level):
            raise ImageIOError(f"cannot read {path}: it has no MIP level {level}")
        spec = inp.spec()
        pixels = None
        if level == 0 and _plain_exr(inp, spec):
            pixels = _read_exr_pixels(path, spec)
        if pixels is None:
            pixels = inp.read_image(0, level, 0, spec.nchannels, oiio.FLOAT)
        if pixels is None or inp.has_error:
            raise ImageIOError(f"cannot read {path}: {_first_line(inp.geterror())}")
        metadata = _tags_from_description({a.name: a.value for a in spec.extra_attribs})
        channels = tuple(spec.channelnames)
        pixel_type = str(spec.format)
    finally:
        inp.close()
    pixels = np.asarray(pixels, np.float32).reshape(spec.height, spec.width, spec.nchannels)
    return np.ascontiguousarray(pixels), channels, metadata, pixel_type


@contextmanager
def _open_input(path: str):
    """An open OIIO ImageInput for ``path`` (closed on exit); one-line errors otherwise."""
    oiio = _oiio()
    if not os.path.isfile(path):
        raise ImageIOError(f"input file not found: {path}")
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise ImageIOError(f"cannot read {path}: {_first_line(oiio.geterror())}")
    try:
        yield inp
    finally:
        inp.close()


def read_header(path: str | os.PathLike, level: int = 0):
    """Read one image file's header without its pixels.

    Returns
    -------
    width, height, channel names, metadata dict (of MIP level ``level``)
    """
    with _open_input(os.fspath(path)) as inp:
        if level and not inp.seek_subimage(0, level):
            raise ImageIOError(f"cannot read {path}: it has no MIP level {level}")
        spec = inp.spec()
        metadata = _tags_from_description({a.name: a.value for a in spec.extra_attribs})
        return spec.width, spec.height, tuple(spec.channelnames), metadata


def read_pixel_type(path: str | os.PathLike) -> str:
    """Pixel type of one image file (``half``, ``float``, ``uint8``...), from its header only."""
    with _open_input(os.fspath(path)) as inp:
        return str(inp.spec().format)


def _first_line(message: str) -> str:
    message = (message or "unknown error").strip()
    return message.splitlines()[0] if message else "unknown error"


_DESCRIPTION_TAG = re.compile(r"\s*envconv:(layout|size|guard|face|level)=(\S+)")


def _tags_from_description(metadata: dict[str, Any]) -> dict[str, Any]:
    """Move envconv tags found in ImageDescription into ``envconv:*`` keys (if not present)."""
    description = metadata.get("ImageDescription")
    if not isinstance(description, str) or "envconv:" not in description:
        return metadata
    for key, value in _DESCRIPTION_TAG.findall(description):
        metadata.setdefault(f"envconv:{key}", value)
    rest = _DESCRIPTION_TAG.sub("", description).strip()
    if rest:
        metadata["ImageDescription"] = rest
    else:
        del metadata["ImageDescription"]
    return metadata
