"""Plain scanline OpenEXR files through the OpenEXR library, where it is faster than OIIO.

OIIO (:mod:`envconv.io`) opens every file and reads its header. A single-part scanline EXR of
half or float channels whose data window is its display window is then decoded by OpenEXR: its
zip decoder (libdeflate) takes half the time of the one OIIO's wheel links. Such a file is also
written by OpenEXR when each attribute has a known OIIO spelling and OpenEXR's single thread is
the cheaper choice. Either way the pixels and attributes are those OIIO would give
(``tests/test_io.py`` checks both directions); anything else goes through OIIO.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np

__all__ = ["is_plain_exr", "read_exr_pixels", "prefer_openexr_writer", "plain_exr_header",
           "write_plain_exr"]  # fmt: skip

log = logging.getLogger(__name__)


def _oiio_threads(name: str, default: int) -> int:
    import OpenImageIO

    return OpenImageIO.get_int_attribute(name, default)


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


def read_exr_pixels(path: str, spec):
    """Pixels (H, W, C) float32 of a plain scanline EXR, in ``spec``'s channel order, decoded by
    the OpenEXR library itself: its zip decoder (libdeflate) takes half the time of the one
    OIIO's wheel links. None when it declines or fails, and OIIO reads the file instead."""
    import OpenEXR

    names = list(spec.channelnames)
    grouped = names in (["R", "G", "B"], ["R", "G", "B", "A"])
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


# Plain scanline EXRs can be written by the OpenEXR library: on one core, 3 × faster than OIIO's
# writer uncompressed and 1.25 × with zip. Only attributes whose OIIO translation is known take this path;
# a file with any other attribute, tiles, MIP levels or a compression level goes through OIIO.
# tests/test_io.py checks that both writers give the same pixels and the same attributes.
_EXR_COMPRESSIONS = {
    "none": "NO_COMPRESSION", "rle": "RLE_COMPRESSION", "zips": "ZIPS_COMPRESSION",
    "zip": "ZIP_COMPRESSION", "piz": "PIZ_COMPRESSION", "pxr24": "PXR24_COMPRESSION",
    "b44": "B44_COMPRESSION", "b44a": "B44A_COMPRESSION",
}  # fmt: skip
_EXR_ENVMAPS = {"LatLong Environment": "ENVMAP_LATLONG", "CubeFace Environment": "ENVMAP_CUBE"}
_EXR_INTEROP_IDS = ("lin_rec709_scene", "lin_ap1_scene", "lin_ap0_scene")


def prefer_openexr_writer(spec) -> bool:
    """The OpenEXR wheel's writer runs on one thread, OIIO's compresses on all of them: use the
    former where compression is cheap (none, rle) or where OIIO has one thread too (batch
    workers), so that the total work is least in a batch and the wall time least alone."""
    compression = spec.get_string_attribute("compression", "zip")
    return compression in ("none", "rle") or _oiio_threads("exr_threads", 0) == 1


def plain_exr_header(spec) -> dict[str, Any] | None:
    """The OpenEXR header OIIO would write for ``spec``, or None when that is not known."""
    import OpenEXR

    if spec.tile_width or str(spec.format) not in ("half", "float") or spec.channelformats:
        return None
    compression = spec.get_string_attribute("compression", "zip")
    if compression not in _EXR_COMPRESSIONS:
        return None
    header: dict[str, Any] = {
        "type": OpenEXR.scanlineimage,
        "compression": getattr(OpenEXR, _EXR_COMPRESSIONS[compression]),
    }
    for attribute in spec.extra_attribs:
        name, kind, value = attribute.name, str(attribute.type), attribute.value
        if name == "compression":
            continue
        if name == "DateTime" and kind == "string":
            header["capDate"] = value
        elif name == "chromaticities" and kind == "float[8]":
            header["chromaticities"] = tuple(value)
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


def write_plain_exr(temp: str, spec, data: np.ndarray) -> bool:
    """Write ``data`` (H, W, C float32) as a plain scanline EXR through the OpenEXR library.
    False, with nothing written, when the file needs OIIO (see _EXR_COMPRESSIONS)."""
    header = plain_exr_header(spec)
    if header is None:
        return False
    import OpenEXR

    names = list(spec.channelnames)
    dtype = np.float16 if str(spec.format) == "half" else np.float32
    if names in (["R", "G", "B"], ["R", "G", "B", "A"]):
        channels = {"".join(names): np.ascontiguousarray(data, dtype)}
    else:
        channels = {n: np.ascontiguousarray(data[:, :, k], dtype) for k, n in enumerate(names)}
    try:
        with OpenEXR.File(header, channels) as exr:
            exr.write(temp)
    except Exception as exc:  # then OIIO writes the file, or says why it cannot
        log.debug("OpenEXR declined %s: %s", temp, exc)
        return False
    return True
