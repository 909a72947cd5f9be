"""One image file to and from float32 pixels and its header, through OpenImageIO and OpenEXR.

This module knows files, not layouts: :mod:`envconv.io` builds environment maps on top of it.
OpenImageIO opens every file and reads every header; the pixels of plain scanline EXRs are
decoded by the OpenEXR library, which is faster at it (:mod:`envconv.io.exr`).

Windows
    An image is its **display window**, as OpenEXR defines it (OIIO's ``full_x``, ``full_y``,
    ``full_width``, ``full_height``; TIFF's XPosition/YPosition give the same). The pixels
    stored, the **data window** (OIIO's ``x``, ``y``, ``width``, ``height``), land where their
    coordinates put them: display-window pixels outside the data window are zero (a *hole*,
    marked 0 in :attr:`FileImage.valid`), and stored pixels outside the display window
    (overscan) are not read into the image.
Parts
    Every part (OIIO subimage) is listed in :class:`FileHeader`. Of a multi-part OpenEXR file
    the parts that are images of the first part's windows (beauty and AOVs of one
    environment: same display and data window, not deep) are read together, their channels
    side by side in part order, the first part's under their own names and the others'
    prefixed ``PART.`` unless they already are; other parts are skipped with a warning.
    ``part=NAME`` (or an index) reads one part alone, of any format.
"""

from __future__ import annotations

import logging
import os
import re
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from ..errors import ImageIOError
from .chatter import library_output
from .exr import is_plain_exr as _plain_exr
from .exr import read_exr_pixels as _read_exr_pixels
from .formats import FORMATS

__all__ = ["read_file", "read_file_header", "read_image", "read_pixel_type",
           "FileHeader", "FileImage", "Part", "FORMATS", "limit_threads", "deep_samples"]  # fmt: skip

log = logging.getLogger(__name__)

#: Pixel types from narrowest to widest: parts read together report the widest.
_WIDTH_ORDER = ("uint8", "int8", "uint16", "int16", "half", "uint", "int", "float", "double")


def _oiio():
    import OpenImageIO

    return OpenImageIO


def limit_threads(threads: int) -> None:
    """Give the image libraries ``threads`` threads (EXR compression and decoding): a batch
    worker's share of the cores. OpenImageIO reads ``OPENIMAGEIO_THREADS`` when first
    imported; once imported, its ``threads`` and ``exr_threads`` attributes are set."""
    os.environ["OPENIMAGEIO_THREADS"] = str(int(threads))
    if "OpenImageIO" in sys.modules:
        oiio = _oiio()
        oiio.attribute("threads", int(threads))
        oiio.attribute("exr_threads", int(threads))


@dataclass(frozen=True)
class Part:
    """One part (OIIO subimage) of a file, at the MIP level read.

    Windows are ``(x, y, width, height)`` in the file's pixel coordinates."""

    index: int
    name: str
    channels: tuple[str, ...]
    channel_types: tuple[str, ...]
    display: tuple[int, int, int, int]
    data: tuple[int, int, int, int]
    deep: bool = False


@dataclass(frozen=True)
class FileHeader:
    """What a file's header says, and which of its parts a read takes (``chosen``)."""

    path: str
    format: str
    level: int
    parts: tuple[Part, ...]
    chosen: tuple[int, ...]
    skipped: tuple[tuple[str, str], ...]
    metadata: dict[str, Any]

    @property
    def first(self) -> Part:
        return self.parts[self.chosen[0]]

    @property
    def display(self) -> tuple[int, int, int, int]:
        return self.first.display

    @property
    def data(self) -> tuple[int, int, int, int]:
        return self.first.data

    @property
    def width(self) -> int:
        return self.display[2]

    @property
    def height(self) -> int:
        return self.display[3]

    @property
    def holes(self) -> bool:
        """True when the data window leaves part of the display window empty."""
        (dx, dy, dw, dh), (x, y, w, h) = self.display, self.data
        return not (x <= dx and y <= dy and x + w >= dx + dw and y + h >= dy + dh)

    @property
    def part_channels(self) -> tuple[tuple[str, tuple[str, ...]], ...]:
        """(part name, its own channel names) of every part read, in order."""
        return tuple((self.parts[i].name, self.parts[i].channels) for i in self.chosen)

    @property
    def channels(self) -> tuple[str, ...]:
        """Channel names of the image read: the first part's, then the others' prefixed."""
        names: list[str] = list(self.first.channels)
        for index in self.chosen[1:]:
            part = self.parts[index]
            names += [
                c if c.startswith(f"{part.name}.") else f"{part.name}.{c}" for c in part.channels
            ]
        return tuple(names)

    @property
    def channel_types(self) -> tuple[str, ...]:
        return tuple(t for i in self.chosen for t in self.parts[i].channel_types)

    @property
    def pixel_type(self) -> str:
        """The widest channel type of the parts read (``half``, ``float``, ``uint8``...)."""
        types = set(self.channel_types)
        return max(types, key=lambda t: _WIDTH_ORDER.index(t) if t in _WIDTH_ORDER else -1)


class FileImage(NamedTuple):
    """A file's image over its display window: ``pixels`` (H, W, C) float32, zero in holes;
    ``valid`` (H, W) float32, 1 where the data window holds the pixel, 0 in holes, or None
    when it holds every pixel."""

    header: FileHeader
    pixels: np.ndarray
    valid: np.ndarray | None


@contextmanager
def _open_input(path: str, config=None):
    """An open OIIO ImageInput for ``path`` (closed on exit); one-line errors otherwise.

    While it is open, what the libraries print is captured (:mod:`envconv.io.chatter`): folded
    into an error raised in the block, logged at debug level otherwise."""
    oiio = _oiio()
    if not os.path.exists(path):
        raise ImageIOError(f"input file not found: {path}")
    if os.path.isdir(path):
        raise ImageIOError(f"input is a directory, not an image: {path}")
    with library_output(f"cannot read {path}", path):
        inp = oiio.ImageInput.open(path) if config is None else oiio.ImageInput.open(path, config)
        if inp is None:
            raise ImageIOError(f"cannot read {path}: {_first_line(oiio.geterror())}")
        try:
            yield inp
        finally:
            inp.close()


def _part(spec, index: int) -> Part:
    nch = spec.nchannels
    types = tuple(str(t) for t in spec.channelformats) or (str(spec.format),) * nch
    return Part(
        index=index,
        name=spec.get_string_attribute("name") or spec.get_string_attribute("oiio:subimagename"),
        channels=tuple(spec.channelnames),
        channel_types=types,
        display=(spec.full_x, spec.full_y, spec.full_width, spec.full_height),
        data=(spec.x, spec.y, spec.width, spec.height),
        deep=bool(spec.deep),
    )


def _header(inp, path: str, level: int, part: str | int | None, deep: bool = False) -> FileHeader:
    """Every part's facts at MIP ``level``, and the choice of parts to read; a first part of
    deep data is refused unless ``deep``."""
    parts, metadata = [], None
    while inp.seek_subimage(len(parts), 0):
        index = len(parts)
        if inp.seek_subimage(index, level):
            parts.append(_part(inp.spec(), index))
        else:
            inp.geterror()  # clear the failed seek's message
            parts.append(None)
        if metadata is None and parts[-1] is not None:
            metadata = {a.name: a.value for a in inp.spec().extra_attribs}
    inp.geterror()  # clear the message of the seek past the last part
    found = [p for p in parts if p is not None]
    if not found:
        raise ImageIOError(f"cannot read {path}: it has no MIP level {level}")
    chosen, skipped = _choose(path, inp.format_name(), parts, part)
    if part is not None or chosen[0] != 0:  # the metadata of the part read
        inp.seek_subimage(chosen[0], level)
        metadata = {a.name: a.value for a in inp.spec().extra_attribs}
    header = FileHeader(path, inp.format_name(), level, tuple(parts), chosen, skipped,
                        _tags_from_description(metadata or {}))  # fmt: skip
    if header.first.deep and not deep:
        flat = [p.name or str(p.index) for p in found if not p.deep]
        fix = (f"pick a flat part with --part ({', '.join(flat)})" if flat else
               f"flatten it first, e.g. oiiotool {path} --flatten -o flat.exr")  # fmt: skip
        raise ImageIOError(f"cannot read {path}: part {header.first.name or 0} holds deep data "
                           f"(any number of samples per pixel), not an image; {fix}")  # fmt: skip
    return header


def _choose(path, fmt, parts, wanted) -> tuple[tuple[int, ...], tuple[tuple[str, str], ...]]:
    """Indices of the parts to read, and (name, why) of those left out."""
    names = [p.name if p and p.name else str(k) for k, p in enumerate(parts)]
    if wanted is not None:
        text = str(wanted)
        hits = [k for k, name in enumerate(names) if name == text]
        if not hits and text.isdigit() and int(text) < len(parts):
            hits = [int(text)]
        if not hits or parts[hits[0]] is None:
            raise ImageIOError(f"{path} has no part {text!r}; its parts: {', '.join(names)}")
        return (hits[0],), tuple((n, "not asked for") for k, n in enumerate(names) if k != hits[0])
    first = parts[0]
    if first is None:
        raise ImageIOError(f"cannot read {path}: its first part has no such MIP level")
    chosen, skipped = [0], []
    for k, part in enumerate(parts[1:], 1):
        if fmt != "openexr":
            why = "only OpenEXR parts are read together; pick one with --part"
        elif part is None:
            why = "no such MIP level"
        elif part.deep:
            why = "deep data"
        elif (part.display, part.data) != (first.display, first.data):
            why = f"its windows differ from part {names[0]}'s"
        else:
            chosen.append(k)
            continue
        skipped.append((names[k], why))
    return tuple(chosen), tuple(skipped)


def read_file_header(path: str | os.PathLike, level: int = 0, part: str | int | None = None,
                     deep: bool = False):  # fmt: skip
    """The :class:`FileHeader` of ``path`` at MIP ``level``, without its pixels; a file whose
    first part (or ``part``) holds deep data is refused unless ``deep``."""
    path = os.fspath(path)
    info = _texture_info(path)
    if info is not None:
        return _texture_header(path, info, level, part)
    with _open_input(path) as inp:
        return _header(inp, path, level, part, deep)


def deep_samples(path: str | os.PathLike, part: int = 0, level: int = 0) -> tuple[int, int]:
    """(fewest, most) samples a pixel of deep part ``part`` holds (reads the deep data)."""
    path = os.fspath(path)
    with _open_input(path) as inp:
        deep = inp.read_native_deep_image(part, level)
        if deep is None or inp.has_error:
            raise ImageIOError(f"cannot read {path}: {_first_line(inp.geterror())}")
    counts = np.fromiter((deep.samples(i) for i in range(deep.pixels)), np.int64, deep.pixels)
    return (int(counts.min()), int(counts.max())) if counts.size else (0, 0)


#: The first bytes of the texture files envconv reads itself (io.dds, io.ktx2): OpenImageIO
#: reads no float DDS and no KTX2.
_TEXTURE_MAGIC = (b"DDS ", bytes([0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB]))


def _texture_info(path: str):
    """The TextureInfo of a DDS or KTX2 file (:mod:`envconv.io.textures`), else None."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(8)
    except OSError:
        return None
    if not any(head.startswith(magic) for magic in _TEXTURE_MAGIC):
        return None
    from .textures import texture_info

    return texture_info(path)


def _texture_header(path: str, info, level: int, part) -> FileHeader:
    """A texture file's header as a one-part image (:mod:`envconv.io.textures`)."""
    from .textures import texture_channels, texture_layout, texture_size

    if part not in (None, 0, "0"):
        raise ImageIOError(f"{path} has no part {str(part)!r}; its parts: 0")
    if not 0 <= level < info.levels:
        raise ImageIOError(f"cannot read {path}: it has no MIP level {level}")
    channels = texture_channels(info)
    window = (0, 0, *texture_size(info, level))
    pixel_type = "half" if info.dtype.endswith("2") else "float"
    first = Part(0, "", channels, (pixel_type,) * len(channels), window, window)
    return FileHeader(path, info.format, level, (first,), (0,), (), texture_layout(info)[1])


def read_file(path: str | os.PathLike, level: int = 0, part: str | int | None = None) -> FileImage:
    """Read an image file over its display window (see the module docstring)."""
    path = os.fspath(path)
    info = _texture_info(path)
    if info is not None:
        from .textures import texture_pixels

        header = _texture_header(path, info, level, part)
        return FileImage(header, texture_pixels(path, info, level), None)
    oiio = _oiio()
    # Alpha is a validity mask, never a compositing alpha: read colour exactly as stored, so
    # OIIO does not premultiply unassociated alpha (PNG, TIFF) on the way in.
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)
    with _open_input(path, config) as inp:
        header = _header(inp, path, level, part)
        stacks = [_read_part(inp, path, index, level) for index in header.chosen]
    if part is None:
        for name, why in header.skipped:
            log.warning("%s: part %s is not read (%s)", path, name, why)
    pixels = stacks[0] if len(stacks) == 1 else np.concatenate(stacks, axis=2)
    pixels, valid = place_in_display(pixels, header.display, header.data)
    return FileImage(header, pixels, valid)


def _read_part(inp, path: str, index: int, level: int) -> np.ndarray:
    """The data window of part ``index`` at ``level``: (h, w, C) float32."""
    oiio = _oiio()
    if not inp.seek_subimage(index, level):
        raise ImageIOError(f"cannot read {path}: {_first_line(inp.geterror())}")
    spec = inp.spec()
    pixels = None
    if level == 0 and _plain_exr(inp, spec):
        pixels = _read_exr_pixels(path, spec)
    if pixels is None:
        pixels = inp.read_image(index, level, 0, spec.nchannels, oiio.FLOAT)
    if pixels is None or inp.has_error:
        raise ImageIOError(f"cannot read {path}: {_first_line(inp.geterror())}")
    pixels = np.asarray(pixels, np.float32).reshape(spec.height, spec.width, spec.nchannels)
    return np.ascontiguousarray(pixels)


def place_in_display(pixels: np.ndarray, display, data) -> tuple[np.ndarray, np.ndarray | None]:
    """``pixels`` of the ``data`` window placed in the ``display`` window (both
    ``(x, y, width, height)``): (image, valid), valid None when no display pixel is empty.
    Overscan (data outside the display window) is cut off."""
    dx, dy, width, height = display
    x, y, w, h = data
    if (x, y, w, h) == (dx, dy, width, height):
        return pixels, None
    left, top = max(x, dx), max(y, dy)
    right, bottom = min(x + w, dx + width), min(y + h, dy + height)
    image = np.zeros((height, width, pixels.shape[2]), np.float32)
    valid = np.zeros((height, width), np.float32)
    if left < right and top < bottom:
        image[top - dy : bottom - dy, left - dx : right - dx] = pixels[
            top - y : bottom - y, left - x : right - x
        ]
        valid[top - dy : bottom - dy, left - dx : right - dx] = 1.0
    return image, (None if valid.all() else valid)


def read_image(path: str | os.PathLike, level: int = 0, part: str | int | None = None):
    """Read one image file as float32 (H, W, C) over its display window (see
    :func:`read_file`; holes are zero).

    Returns
    -------
    pixels, channel names, metadata dict, pixel type (``half``/``float``/``uint8``/``uint16``)
    """
    image = read_file(path, level, part)
    header = image.header
    return image.pixels, header.channels, header.metadata, header.pixel_type


def read_pixel_type(path: str | os.PathLike, part: str | int | None = None) -> str:
    """Pixel type of one image file (``half``, ``float``, ``uint8``...), from its header only."""
    return read_file_header(path, 0, part).pixel_type


def _first_line(message: str) -> str:
    message = (message or "unknown error").strip()
    return message.splitlines()[0] if message else "unknown error"


_DESCRIPTION_TAG = re.compile(r"\s*envconv:(layout|size|guard|face|level|grid|view)=(\S+)")


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
