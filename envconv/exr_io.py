"""Plain scanline OpenEXR files through the OpenEXR library, where it is faster than OIIO.

A plain EXR is a single-part scanline file of half or float channels whose data window is its
display window. OpenEXR's zip codec (libdeflate) takes half the time of the one OIIO's wheel
links, and OpenEXR's thread pool gets the thread count OIIO's ``exr_threads`` names (all cores
by default, one in a batch worker), so both libraries use the cores alike: on two cores OpenEXR
decodes a 2048×1024 zip float in 0.03 s against OIIO's 0.12 s, and writes a 512 cross with zip
in 0.14 s against 0.19–0.25 s.

- Reading: a plain RGB or RGBA file whose attributes all have a known OIIO reading (for the
  installed OIIO version) is read by OpenEXR alone, header included (:func:`read_plain_exr`,
  :func:`read_plain_exr_header`), and OIIO is not even imported
  (0.035 s of a one-shot command); other plain files are opened by OIIO and decoded by OpenEXR
  (:func:`read_exr_pixels`); anything else is read by OIIO.
- Writing: a plain file is written by OpenEXR when each attribute has a known OIIO spelling
  (:func:`plain_exr_header`), else by OIIO.

Either way the pixels, channels and attributes are those OIIO would give or write
(``tests/test_io.py`` checks both directions).
"""

from __future__ import annotations

import functools
import logging
import os
import sys
import time
from typing import Any

import numpy as np

__all__ = ["is_plain_exr", "read_exr_pixels", "read_plain_exr", "read_plain_exr_header",
           "prefer_openexr_writer", "plain_exr_header", "write_plain_exr"]  # fmt: skip

log = logging.getLogger(__name__)


def _oiio_threads(name: str, default: int) -> int:
    """OIIO's thread-count attribute ``name``. When OIIO is not loaded and no environment
    variable sets its options, it would answer ``default`` (all cores): OIIO is not imported
    just to say so."""
    if "OpenImageIO" not in sys.modules and not (
        os.environ.get("OPENIMAGEIO_THREADS") or os.environ.get("OPENIMAGEIO_OPTIONS")
    ):
        return default
    import OpenImageIO

    return OpenImageIO.get_int_attribute(name, default)


def _set_openexr_threads(compression: str = "zip", threads: int | None = None) -> None:
    """Size OpenEXR's global thread pool from OIIO's ``exr_threads`` (0: all cores), or to
    ``threads`` when given.

    Uncompressed and RLE data gain nothing from helper threads (0.047 s alone against 0.06 s on
    two for a 512 cross), so those run on the calling thread. The pool is resized only when the
    count changes (about 3 ms to shrink, 0.1 ms to grow)."""
    import OpenEXR

    setter = getattr(OpenEXR, "set_global_thread_count", None)
    if setter is None:  # OpenEXR < 3.3: single-threaded
        return
    if threads is None:
        threads = _oiio_threads("exr_threads", 0)
    if threads <= 0:
        threads = os.cpu_count() or 1
    if threads == 1 or compression in ("none", "rle"):
        threads = 0  # OpenEXR's "no pool": the calling thread does the work
    if OpenEXR.global_thread_count() != threads:
        setter(threads)


def is_plain_exr(inp, spec) -> bool:
    """True for a single-part scanline OpenEXR file of half or float channels whose data
    window is its display window: what :func:`read_exr_pixels` decodes."""
    return (
        inp.format_name() == "openexr"
        and spec.tile_width == 0
        and not spec.deep
        and spec.get_int_attribute("oiio:subimages", 1) == 1
        and (spec.x, spec.y, spec.width, spec.height)
        == (spec.full_x, spec.full_y, spec.full_width, spec.full_height)
        and str(spec.format) in ("half", "float")
        and all(str(f) in ("half", "float") for f in spec.channelformats)
    )


def read_exr_pixels(path: str, spec, threads: int | None = None):
    """Pixels (H, W, C) float32 of a plain scanline EXR, in ``spec``'s channel order, decoded by
    the OpenEXR library itself: its zip decoder (libdeflate) takes half the time of the one
    OIIO's wheel links. None when it declines or fails, and OIIO reads the file instead.
    ``threads`` overrides OIIO's ``exr_threads`` (see :func:`_set_openexr_threads`)."""
    import OpenEXR

    names = list(spec.channelnames)
    grouped = names in (["R", "G", "B"], ["R", "G", "B", "A"])
    _set_openexr_threads(spec.get_string_attribute("compression", "zip"), threads)
    try:
        with OpenEXR.File(path, separate_channels=not grouped) as exr:
            channels = exr.channels()
            if grouped:
                data = channels.get("".join(names))
                return None if data is None else data.pixels.astype(np.float32, copy=False)
            pixels = np.empty((spec.height, spec.width, len(names)), np.float32)
            for k, name in enumerate(names):
                if name not in channels:
                    return None
                pixels[..., k] = channels[name].pixels
            return pixels
    except Exception:  # damaged, or subsampled channels: OIIO reads it or says why not
        return None


# What OIIO's OpenEXR reader (3.x) makes of a plain file's header, for read_plain_exr. It takes
# ``envmap`` first, then the compression, then every other attribute in the header's (sorted)
# order, renamed as below, and ends with the subimage count and the colour space that
# ``colorInteropID`` names. Any attribute not listed sends the file to OIIO.
_OIIO_ROWS_PER_CHUNK = {"zip": 16, "pxr24": 16, "piz": 32, "b44": 32, "b44a": 32, "dwaa": 32,
                        "dwab": 256}  # fmt: skip
# The reader also knows DWA (a file's DWA level is an attribute of its own, unknown here).
_EXR_READ_COMPRESSIONS = {"dwaa": "DWAA_COMPRESSION", "dwab": "DWAB_COMPRESSION"}
_OIIO_LINE_ORDERS = {"INCREASING_Y": "increasingY", "DECREASING_Y": "decreasingY",
                     "RANDOM_Y": "randomY"}  # fmt: skip
_STRUCTURAL = {"channels", "compression", "dataWindow", "displayWindow", "type", "envmap"}


#: OIIO versions (major.minor) whose reading of a plain header :func:`_oiio_metadata` gives,
#: as tests/test_io.py checks against OIIO itself. With any other, OIIO reads every file.
_OIIO_READINGS_KNOWN = ("3.2",)


@functools.cache
def _oiio_reading_known() -> bool:
    """Whether the installed OIIO is one whose reading :func:`_oiio_metadata` reproduces (its
    version from the installed distribution, so that OIIO need not be imported)."""
    oiio = sys.modules.get("OpenImageIO")
    if oiio is not None:
        version = getattr(oiio, "__version__", None)
    else:
        from ._versions import installed_version

        version = installed_version("OpenImageIO")
    if version is None:  # not installed as a distribution: OIIO reads
        return False
    return ".".join(str(version).split(".")[:2]) in _OIIO_READINGS_KNOWN


def _oiio_metadata(header: dict[str, Any]) -> dict[str, Any] | None:
    """The attributes (name → value, in OIIO's order) OIIO's ImageSpec holds for a plain file
    with this OpenEXR ``header``, or None when one of them has no known OIIO reading."""
    import OpenEXR

    compressions = {**_EXR_COMPRESSIONS, **_EXR_READ_COMPRESSIONS}.items()
    compression = {getattr(OpenEXR, v): k for k, v in compressions}.get(header.get("compression"))
    if compression is None or header.get("type", OpenEXR.scanlineimage) != OpenEXR.scanlineimage:
        return None
    metadata: dict[str, Any] = {}
    envmap = header.get("envmap")
    if envmap is not None:
        if envmap == OpenEXR.Envmap.ENVMAP_LATLONG:
            metadata.update({"textureformat": "LatLong Environment", "oiio:updirection": "y"})
        elif envmap == OpenEXR.Envmap.ENVMAP_CUBE:
            metadata["textureformat"] = "CubeFace Environment"
        else:
            return None
        metadata["oiio:sampleborder"] = 1
    metadata["compression"] = compression
    if compression in _OIIO_ROWS_PER_CHUNK:
        metadata["oiio:RowsPerChunk"] = _OIIO_ROWS_PER_CHUNK[compression]
    for name in sorted(header):
        value = header[name]
        if name in _STRUCTURAL:
            continue
        if name == "capDate" and isinstance(value, str):
            metadata["DateTime"] = value
        elif name == "chromaticities" and isinstance(value, tuple) and len(value) == 8:
            metadata["chromaticities"] = tuple(float(v) for v in value)
        elif name == "lineOrder" and getattr(value, "name", None) in _OIIO_LINE_ORDERS:
            metadata["openexr:lineOrder"] = _OIIO_LINE_ORDERS[value.name]
        elif name == "pixelAspectRatio" and isinstance(value, float):
            metadata["PixelAspectRatio"] = value
        elif name == "screenWindowCenter" and np.shape(value) == (2,):
            metadata["screenWindowCenter"] = tuple(float(v) for v in value)
        elif name == "screenWindowWidth" and isinstance(value, float):
            metadata["screenWindowWidth"] = value
        elif name in ("colorInteropID", "textureformat", "Software") and isinstance(value, str):
            metadata[name] = value
        elif name.startswith("envconv:") and type(value) in (str, int):
            metadata[name] = value
        else:
            return None
    metadata["oiio:subimages"] = 1
    if "colorInteropID" in metadata:
        metadata["oiio:ColorSpace"] = metadata["colorInteropID"]
    return metadata


def read_plain_exr_header(path: str):
    """(width, height, channel names, metadata) of a plain RGB or RGBA scanline EXR, read by
    the OpenEXR library alone, exactly as OIIO would give them (metadata as OIIO's ImageSpec
    attributes, in OIIO's order). None when the file is anything else, has an attribute whose
    OIIO reading is not known here, or cannot be read: then OIIO reads it or says why not."""
    if not _oiio_reading_known():
        return None
    import OpenEXR

    try:
        with OpenEXR.File(path, header_only=True) as exr:  # its header lasts as long as it
            header = exr.header()
            if len(exr.parts) != 1:
                return None
            low, high = (np.array(corner) for corner in header["dataWindow"])
            display = [np.array(corner) for corner in header["displayWindow"]]
            names = tuple(sorted((c.name for c in header["channels"]), key="RGBA".find))
            samplings = {(c.xSampling, c.ySampling) for c in header["channels"]}
            metadata = _oiio_metadata(header)
    except Exception:  # not an OpenEXR file, or damaged: OIIO says why
        return None
    if names not in (("R", "G", "B"), ("R", "G", "B", "A")) or samplings != {(1, 1)}:
        return None
    if not (np.array_equal(low, display[0]) and np.array_equal(high, display[1])):
        return None
    if metadata is None:
        return None
    width, height = (high - low + 1).tolist()
    return width, height, names, metadata


def read_plain_exr(path: str, threads: int | None = None):
    """(pixels (H, W, C) float32, channel names, metadata, pixel type) of a plain RGB or RGBA
    scanline EXR, read by the OpenEXR library alone, as OIIO would give them; None otherwise
    (see :func:`read_plain_exr_header`). ``threads`` as for :func:`read_exr_pixels`."""
    import OpenEXR

    found = read_plain_exr_header(path)
    if found is None:
        return None
    width, height, names, metadata = found
    _set_openexr_threads(metadata["compression"], threads)
    try:
        with OpenEXR.File(path) as exr:
            channels = exr.channels()
            if list(channels) != ["".join(names)]:
                return None
            pixels = channels["".join(names)].pixels
    except Exception:  # mixed pixel types, or damaged: OIIO reads it or says why not
        return None
    pixel_type = {np.dtype(np.float16): "half", np.dtype(np.float32): "float"}.get(pixels.dtype)
    if pixel_type is None or pixels.shape != (height, width, len(names)):
        return None
    return np.ascontiguousarray(pixels, np.float32), names, metadata, pixel_type


# Plain scanline EXRs can be written by the OpenEXR library: on one core, 3 × faster than OIIO's
# writer uncompressed and 1.25 × with zip; with its thread pool, also faster on all cores. Only
# attributes whose OIIO translation is known take this path;
# a file with any other attribute, tiles, MIP levels or a compression level goes through OIIO.
# tests/test_io.py checks that both writers give the same pixels and the same attributes.
_EXR_COMPRESSIONS = {
    "none": "NO_COMPRESSION", "rle": "RLE_COMPRESSION", "zips": "ZIPS_COMPRESSION",
    "zip": "ZIP_COMPRESSION", "piz": "PIZ_COMPRESSION", "pxr24": "PXR24_COMPRESSION",
    "b44": "B44_COMPRESSION", "b44a": "B44A_COMPRESSION",
}  # fmt: skip
_EXR_ENVMAPS = {"LatLong Environment": "ENVMAP_LATLONG", "CubeFace Environment": "ENVMAP_CUBE"}
_EXR_INTEROP_IDS = ("lin_rec709_scene", "lin_ap1_scene", "lin_ap0_scene")


def _compression(attributes) -> str:
    """The compression an image with these ImageSpec ``attributes`` is written with (OIIO's
    default for OpenEXR: zip)."""
    return dict(attributes).get("compression", "zip")


def prefer_openexr_writer(attributes) -> bool:
    """Whether to try the OpenEXR writer first, for an image with these ImageSpec
    ``attributes`` ((name, value) pairs). With its thread pool sized like OIIO's it is faster
    for every lossless compression measured (zip 0.14 s against 0.19–0.25 s, none 0.05 s
    against 0.10 s, piz 0.35 s against 0.49 s for a 512 cross on two cores); an attribute or a
    compression level it cannot spell still sends the file to OIIO (:func:`plain_exr_header`)."""
    return _compression(attributes) in _EXR_COMPRESSIONS


def _oiio_kind(value) -> str | None:
    """The type OIIO's ImageSpec gives ``value`` when envconv sets it (``io._set_attribute``);
    None for what is not spelled here."""
    if type(value) in (str, int, float):
        return {str: "string", int: "int", float: "float"}[type(value)]
    if isinstance(value, (tuple, list)) and value and type(value[0]) in (int, float):
        return f"{'float' if type(value[0]) is float else 'int'}[{len(value)}]"
    return None


def plain_exr_header(image) -> dict[str, Any] | None:
    """The OpenEXR header OIIO would write for ``image`` (an :class:`envconv.io.LevelImage`:
    untiled, one pixel type for every channel), or None when that is not known."""
    import OpenEXR

    if image.pixel_type not in ("half", "float"):
        return None
    compression = _compression(image.attributes)
    if compression not in _EXR_COMPRESSIONS:
        return None
    header: dict[str, Any] = {
        "type": OpenEXR.scanlineimage,
        "compression": getattr(OpenEXR, _EXR_COMPRESSIONS[compression]),
    }
    for name, value in image.attributes:
        kind = _oiio_kind(value)
        if name == "compression":
            continue
        if name == "DateTime" and kind == "string":
            header["capDate"] = value
        elif name == "chromaticities" and kind == "float[8]":
            header["chromaticities"] = tuple(float(v) for v in value)
        elif name == "oiio:ColorSpace" and value in _EXR_INTEROP_IDS:
            header["colorInteropID"] = value
        elif name == "textureformat" and value in _EXR_ENVMAPS:
            header["textureformat"] = value
            header["envmap"] = getattr(OpenEXR.Envmap, _EXR_ENVMAPS[value])
        elif (name == "Software" or name.startswith("envconv:")) and kind in ("string", "int"):
            header[name] = value
        else:
            return None
    # OIIO stamps the time of writing when the image carries none.
    header.setdefault("capDate", time.strftime("%Y:%m:%d %H:%M:%S"))
    return header


def write_plain_exr(temp: str, image) -> bool:
    """Write ``image`` (an :class:`envconv.io.LevelImage`) as a plain scanline EXR through the
    OpenEXR library. False, with nothing written, when the file needs OIIO (see
    :func:`plain_exr_header`)."""
    header = plain_exr_header(image)
    if header is None:
        return False
    import OpenEXR

    names, data = list(image.channels), image.data
    dtype = np.float16 if image.pixel_type == "half" else np.float32
    if names in (["R", "G", "B"], ["R", "G", "B", "A"]):
        channels = {"".join(names): np.ascontiguousarray(data, dtype)}
    else:
        channels = {n: np.ascontiguousarray(data[:, :, k], dtype) for k, n in enumerate(names)}
    _set_openexr_threads(_compression(image.attributes))
    try:
        with OpenEXR.File(header, channels) as exr:
            exr.write(temp)
    except Exception as exc:  # then OIIO writes the file, or says why it cannot
        log.debug("OpenEXR declined %s: %s", temp, exc)
        return False
    return True
