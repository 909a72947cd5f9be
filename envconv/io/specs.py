"""What one written image carries, before and as OpenImageIO sees it: its channels, pixel
type and attributes (:class:`LevelImage`), envconv's layout tags, and its ImageSpec.

Used by :mod:`envconv.io.writer`; nothing here opens a file.
"""

from __future__ import annotations

import logging
import os
from typing import Any, NamedTuple

import numpy as np

from ..envmap import EnvMap, alpha_channel
from ..layouts.grids import CENTRES, tagged_grid
from ..layouts.view import VIEW_TAG, view_text
from .exr_header import PLACEHOLDER
from .files import _oiio
from .formats import choose_pixel_type, format_of
from .write_plan import stored_channels

__all__ = ["LevelImage", "level_image", "image_spec", "set_mip_attributes"]

log = logging.getLogger(__name__)


def _int_tag(fmt: str, value: int):
    """An integer tag as the format can keep it: PNG and JPEG keep only text attributes."""
    return str(int(value)) if fmt in ("png", "jpeg") else int(value)


def set_mip_attributes(spec, fmt: str) -> None:
    """Tiled MIP-map attributes: EXR MIPMAP_LEVELS with ROUND_DOWN, TIFF MIP directories."""
    spec.tile_width = spec.tile_height = 64
    if fmt == "openexr":
        spec.attribute("openexr:levelmode", 1)  # MIPMAP_LEVELS
        spec.attribute("openexr:roundingmode", 0)  # ROUND_DOWN
    if not spec.get_string_attribute("textureformat"):
        spec.attribute("textureformat", "Plain Texture")


class LevelImage(NamedTuple):
    """One image as it is to be written, before any image library is involved.

    ``attributes`` are the (name, value) pairs its OIIO ImageSpec gets, in that order (see
    :func:`image_spec`); ``data`` is (H, W, C) float32 holding the values to store (codes,
    half or float, from :func:`envconv.io.encode.encode_output`)."""

    format: str
    channels: tuple[str, ...]
    pixel_type: str
    alpha_index: int | None
    attributes: list[tuple[str, Any]]
    data: np.ndarray


def level_image(target, pixels, envmap: EnvMap, face, bit_depth, compression, level=None,
                 channels=None):  # fmt: skip
    """The :class:`LevelImage` of one image of ``envmap`` written to ``target`` (of one of
    its parts when ``channels`` names that part's channels)."""
    fmt = format_of(target)[0]
    pixel_type = choose_pixel_type(target, envmap.pixel_type, bit_depth)
    channels = list(envmap.channels if channels is None else channels)
    kept = list(stored_channels(target, channels))
    if len(kept) < len(channels):
        log.warning("%s stores at most %d channels; writing %s", fmt, len(kept), ",".join(kept))
    if len(kept) <= len(channels) and kept != channels:
        pixels = _take(pixels, range(len(kept)))
    elif len(kept) > len(channels):  # Radiance HDR: one channel repeated into RGB
        pixels = _take(pixels, [0] * len(kept))
    channels = kept
    nch = pixels.shape[2]
    alpha = alpha_channel(channels[:nch])
    attributes: list[tuple[str, Any]] = []
    if alpha is not None and fmt in ("png", "tiff", "targa"):
        # Store alpha unassociated: OIIO would otherwise divide colour by it (PNG, Targa) or
        # mark it premultiplied (TIFF). envconv's alpha is a validity mask.
        attributes.append(("oiio:UnassociatedAlpha", 1))
    if fmt == "targa":
        # Uncompressed (type 2) and stored bottom-up, the Targa default: Quake II's loader
        # reads rows bottom-up whatever the header says, and reads no other image types
        # than 2 and 10; OIIO writes RLE top-down.
        attributes.append(("compression", "none"))
    attributes.extend(envmap.metadata.items())
    attributes.extend(_envconv_tags(envmap, fmt, face))
    if compression is not None:
        attributes.append(("compression", compression))
    if level is not None:
        attributes.append(("envconv:level", _int_tag(fmt, level)))
    data = pixels if hasattr(pixels, "rows") else np.ascontiguousarray(pixels)
    return LevelImage(fmt, tuple(channels), pixel_type, alpha, attributes, data)


def _take(pixels, channels):
    """``pixels[:, :, channels]`` of an array or of a lazily encoded level."""
    channels = list(channels)
    return pixels.take(channels) if hasattr(pixels, "rows") else pixels[:, :, channels]


def image_spec(image: LevelImage):
    """The OIIO ImageSpec of ``image``."""
    oiio = _oiio()
    height, width, nch = image.data.shape
    spec = oiio.ImageSpec(width, height, nch, getattr(oiio, image.pixel_type.upper()))
    spec.channelnames = image.channels
    if image.alpha_index is not None:
        spec.alpha_channel = image.alpha_index
    for name, value in image.attributes:
        _set_attribute(spec, name, value)
    return spec


# TIFF, Radiance HDR and JPEG keep only the attributes their format defines, so envconv's
# layout tags also travel in ImageDescription, as "envconv:layout=NAME envconv:size=N ...".
_DESCRIPTION_FORMATS = ("tiff", "hdr", "jpeg")


def _envconv_tags(envmap: EnvMap, fmt: str, face: str | None) -> list[tuple[str, Any]]:
    """The attributes that tag a file as envconv's: layout, size, guard, version, face, and
    OpenEXR's envmap (through OIIO's ``textureformat``)."""
    from .. import __version__

    tags: list[tuple[str, Any]] = []
    grid = tagged_grid(envmap.metadata)
    view = view_text(envmap.layout.view_options) if envmap.layout.view else None
    if fmt in _DESCRIPTION_FORMATS:
        words = {"layout": envmap.layout.name, "size": envmap.size, "guard": envmap.guard}
        if face is not None:
            words["face"] = face
        if grid != CENTRES:
            words["grid"] = grid
        if view is not None:
            words["view"] = view.replace(" ", ";")
        text = " ".join(f"envconv:{k}={v}" for k, v in words.items())
        kept = str(envmap.metadata.get("ImageDescription", "")).strip()
        tags.append(("ImageDescription", f"{kept} {text}".strip()))

    tags += [
        ("envconv:layout", envmap.layout.name),
        ("envconv:size", _int_tag(fmt, envmap.size)),
        ("envconv:guard", _int_tag(fmt, envmap.guard)),
        ("envconv:version", __version__),
        ("Software", f"envconv {__version__}"),
    ]
    if face is not None:
        tags.append(("envconv:face", face))
    if view is not None:
        tags.append((VIEW_TAG, view))
    stamp = _source_date()
    if stamp is not None and "DateTime" not in envmap.metadata:
        tags.append(("DateTime", stamp))
    if fmt == "openexr" and envmap.guard == 0:
        tags += _envmap_tags(envmap.layout.name, grid)
    return tags


def _envmap_tags(layout: str, grid: str) -> list[tuple[str, Any]]:
    """OpenEXR's ``envmap`` attribute (through OIIO's ``textureformat``: a plain "envmap"
    string would be stored with the wrong type and make the file unreadable) and where its
    samples sit. OIIO reads ``envmap`` as samples on the edges (OpenEXR's ImfEnvmap), so a map
    on pixel centres also gets ``oiio:sampleborder = 0``, stored under a placeholder name
    (:mod:`envconv.io.exr_header`). A Mitsuba grid (rows on the edges, columns centred) is
    neither, so it is not tagged as an envmap at all."""
    if layout == "cube-exr":
        return [("textureformat", "CubeFace Environment"), (PLACEHOLDER, 0)]
    if layout != "latlong" or grid == "edge-rows":
        return []
    tags: list[tuple[str, Any]] = [("textureformat", "LatLong Environment")]
    if grid == CENTRES:
        tags.append((PLACEHOLDER, 0))
    return tags


def _source_date() -> str | None:
    """``DateTime`` from ``SOURCE_DATE_EPOCH`` (reproducible builds: the same inputs give the
    same bytes, whenever and however often they are written), else None: OpenImageIO stamps
    the time of writing."""
    value = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
    if not value.isdigit():
        return None
    import time

    return time.strftime("%Y:%m:%d %H:%M:%S", time.gmtime(int(value)))


def _set_attribute(spec, name: str, value: Any) -> None:
    try:
        if isinstance(value, (str, int, float)):
            spec.attribute(name, value)
        elif isinstance(value, (tuple, list)) and value:
            oiio = _oiio()
            kind = oiio.FLOAT if isinstance(value[0], float) else oiio.INT
            spec.attribute(
                name,
                oiio.TypeDesc(f"{'float' if kind == oiio.FLOAT else 'int'}[{len(value)}]"),
                value,
            )
    except Exception as exc:  # metadata that OIIO cannot express is dropped, not fatal
        log.debug("dropped metadata %s: %s", name, exc)
