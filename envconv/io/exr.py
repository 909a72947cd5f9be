"""Scanline OpenEXR pixels decoded by OpenEXR's own Python API, where it is faster than OIIO.

OpenImageIO opens every file and reads every header, so the channels and metadata envconv sees
are always OIIO's. For a single-part scanline file of half or float channels, the pixels are
then decoded by the ``OpenEXR`` module's public API (``OpenEXR.File``) instead of OIIO's
``read_image``: OpenEXR's zip decoder is two to six times faster than the one OIIO's wheel links.
``python benchmarks/exr_io.py`` (one process, both libraries on every core; 2 cores, OIIO
3.2.2, OpenEXR 3.5.3; the range of two runs on a shared machine, medians of 9 reads):

============================  ===============  =========================
RGB file                      OIIO             OIIO header + OpenEXR
============================  ===============  =========================
2048×1024 float, zip          176–340 ms       46–188 ms
2048×1024 half, zip           151–187 ms       27–28 ms
2048×1024 float, none         45–83 ms         12–23 ms
2048×1024 float, piz          283–415 ms       213–316 ms
4096×2048 float, zip          997–1149 ms      383–468 ms
4096×2048 half, piz           906–1524 ms      908–910 ms
============================  ===============  =========================

Writing showed no consistent gain (2048×1024 float zip 494–808 ms with OIIO against 501–739 ms;
4096×2048 half zip 1152–1902 ms against 1460–1469 ms) and would need OIIO's attribute
spellings reproduced, so every file is written by OIIO. Any file this module
declines, or fails to decode, is read by OIIO, which also reports the errors.
"""

from __future__ import annotations

import os
import threading
from contextlib import contextmanager

import numpy as np

__all__ = ["is_plain_exr", "read_exr_pixels"]


#: Decodes by OpenEXR in flight in this process (any thread), and its lock: the pool is a
#: process global, resized only when no decode is using it.
_decoding = {"count": 0}
_decoding_lock = threading.Lock()


@contextmanager
def _openexr_pool(compression: str):
    """Size OpenEXR's pool for ``compression`` (:func:`_set_openexr_threads`) unless another
    thread is decoding with it (a Dask worker reading two files at once): then the decode
    takes the pool as it is, which changes its speed, never its pixels."""
    with _decoding_lock:
        if _decoding["count"] == 0:
            _set_openexr_threads(compression)
        _decoding["count"] += 1
    try:
        yield
    finally:
        with _decoding_lock:
            _decoding["count"] -= 1


def _set_openexr_threads(compression: str) -> None:
    """Size OpenEXR's global thread pool like OIIO's for OpenEXR: its public ``exr_threads``
    attribute (0: every core; one in a batch worker). Uncompressed and RLE data decode faster
    on the calling thread alone (OpenEXR's count 0): 2048×1024 float RGB in 11–18 ms against
    22–28 ms on a pool of two."""
    import OpenEXR
    import OpenImageIO

    setter = getattr(OpenEXR, "set_global_thread_count", None)
    if setter is None:  # OpenEXR < 3.3 has no pool to size
        return
    threads = OpenImageIO.get_int_attribute("exr_threads", 0)
    if threads <= 0:
        threads = os.cpu_count() or 1
    if threads == 1 or compression in ("none", "rle"):
        threads = 0
    if OpenEXR.global_thread_count() != threads:
        setter(threads)


def is_plain_exr(inp, spec) -> bool:
    """True for a single-part scanline OpenEXR file of half or float channels (``inp`` an
    open OIIO ImageInput, ``spec`` its ImageSpec): what :func:`read_exr_pixels` decodes."""
    return (
        inp.format_name() == "openexr"
        and spec.tile_width == 0
        and not spec.deep
        and spec.get_int_attribute("oiio:subimages", 1) == 1
        and str(spec.format) in ("half", "float")
        and all(str(f) in ("half", "float") for f in spec.channelformats)
    )


def read_exr_pixels(path: str, spec):
    """Pixels (H, W, C) float32 of a plain scanline EXR's data window (:func:`is_plain_exr`),
    in ``spec``'s channel order, decoded by the OpenEXR library. None when it declines or fails (subsampled
    channels, a damaged file): then OIIO reads the file, or says why it cannot."""

    with _openexr_pool(spec.get_string_attribute("compression", "zip")):
        return _decode(path, spec)


def _decode(path: str, spec):
    """:func:`read_exr_pixels` with OpenEXR's pool sized."""
    import OpenEXR

    names = list(spec.channelnames)
    grouped = names in (["R", "G", "B"], ["R", "G", "B", "A"])
    if any(str(f) == "half" for f in (spec.channelformats or [spec.format])):
        return _read_half_bands(path, spec, names)
    try:
        with OpenEXR.File(path, separate_channels=not grouped) as exr:
            channels = exr.channels()
            if grouped:
                data = channels.get("".join(names))
                pixels = None if data is None else data.pixels.astype(np.float32, copy=False)
            else:
                pixels = np.empty((spec.height, spec.width, len(names)), np.float32)
                for k, name in enumerate(names):
                    if name not in channels:
                        return None
                    pixels[..., k] = channels[name].pixels
    except Exception:  # damaged, or subsampled channels: OIIO reads it or says why not
        return None
    if pixels is None or pixels.shape != (spec.height, spec.width, len(names)):
        return None
    return pixels


#: Scanlines decoded per call for half data: a multiple of every compression's block (1, 16,
#: 32 or 256 lines), small enough that the half copy of a band is noise beside the image.
HALF_BAND_ROWS = 256


def _read_half_bands(path: str, spec, names: list[str]):
    """Half channels decoded band by band into one float32 array, so reading never holds a
    half copy of the whole image beside it (peak 1.0x the float32 pixels, not 1.5x:
    docs/memory.md). OpenEXR's ``InputFile.channels`` decodes a range of scanlines of several
    channels at once, as fast as ``OpenEXR.File`` decodes the whole image (4096x2048 half zip:
    0.15 s either way, on 2 cores). None when it declines or fails, as for
    :func:`read_exr_pixels`."""
    import OpenEXR

    try:
        exr = OpenEXR.InputFile(path)
        try:
            header = exr.header()["channels"]
            if any(name not in header for name in names):
                return None
            pixels = np.empty((spec.height, spec.width, len(names)), np.float32)
            for y0 in range(0, spec.height, HALF_BAND_ROWS):
                y1 = min(spec.height, y0 + HALF_BAND_ROWS)
                planes = exr.channels(names, header[names[0]].type, spec.y + y0, spec.y + y1 - 1)
                for k, (name, plane) in enumerate(zip(names, planes, strict=True)):
                    kind = np.float16 if str(header[name].type) == "HALF" else np.float32
                    if header[name].type != header[names[0]].type:
                        plane = exr.channel(name, header[name].type, spec.y + y0, spec.y + y1 - 1)
                    pixels[y0:y1, :, k] = np.frombuffer(plane, kind).reshape(y1 - y0, spec.width)
        finally:
            exr.close()
    except Exception:  # damaged, or subsampled channels: OIIO reads it or says why not
        return None
    return pixels
