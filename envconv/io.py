"""Reading and writing environment maps: the file side of envconv.

Formats: OpenEXR (half or float), Radiance HDR, TIFF, PNG and JPEG, chosen by the file
extension. Pixels are always float32 in memory, in scene-linear Rec.709: :func:`read` and
:func:`write` convert colour, range and bit depth through :mod:`envconv.colorflow`.

Multi-file layouts (cube-faces, paraboloid-split) name their parts with ``{face}`` in the path:
px nx py ny pz nz, or front back.

This module reads maps (files through :mod:`envconv.file_io`); writing lives in
:mod:`envconv.io_write` (every output goes to a temporary file renamed into place, so a failure
never leaves a partial file, and inputs are never opened for writing) and is re-exported here.
"""

from __future__ import annotations

import logging
import os
from typing import Any

import numpy as np

from .detect import detect_layout
from .envmap import EnvMap
from .errors import ImageIOError, LayoutError
from .file_io import _open_input, read_header, read_image, read_pixel_type
from .formats import FORMATS, choose_pixel_type
from .io_write import output_paths, write
from .layouts import get_layout

__all__ = ["read", "write", "read_image", "read_header", "read_pixel_type", "choose_pixel_type",
           "output_paths", "mip_levels", "FORMATS"]

log = logging.getLogger(__name__)

# Metadata that describes a file's encoding rather than its content; never copied to an output.
_DROP_PREFIXES = ("oiio:", "envconv:", "openexr:", "tiff:", "png:", "jpeg:", "exif:", "hdr:")
_DROP_NAMES = {"envmap", "compression", "planarconfig", "Orientation", "XResolution",
               "YResolution", "ResolutionUnit", "PixelAspectRatio", "screenWindowCenter",
               "screenWindowWidth", "tile_width", "tile_height", "Software", "textureformat"}  # fmt: skip
_KEEP_NAMES = {"oiio:ColorSpace"}


def read(
    path: str | os.PathLike,
    layout: str | None = None,
    level: int = 0,
    input_colorspace: str | None = None,
    ocio_config: str | os.PathLike | None = None,
) -> EnvMap:
    """Read an environment map, in scene-linear float32 (linear Rec.709).

    Parameters
    ----------
    path : str or path
        Image file. Multi-file layouts use ``{face}`` in the path.
    layout : str, optional
        Layout name (``--from``); detected from metadata or the aspect ratio when omitted.
    level : int
        MIP level to read (0, the full resolution, by default).
    input_colorspace : str, optional
        Colour space of the file's pixels (an OCIO name or alias); default its
        ``oiio:ColorSpace``, else linear for float/half and sRGB for 8/16-bit data.
    ocio_config : str or path, optional
        OpenColorIO config; default ``$OCIO``, else ``ocio://default``.

    Pixels are converted to linear Rec.709 by :func:`envconv.colorflow.to_working`. A
    lat-long stored with edge-aligned samples (``oiio:sampleborder``, as OpenEXR envmaps
    written by other tools) is resampled onto pixel centres
    (:func:`envconv.colorflow.resample_edge_aligned`).
    """
    from .colorflow import to_working

    path = os.fspath(path)
    if "{face}" in path:
        return to_working(_read_multi(path, layout, level), input_colorspace, ocio_config)
    if layout is not None and get_layout(layout).multi_file:
        raise LayoutError(f"layout {layout} is stored as several files; put {{face}} in the path")
    pixels, channels, metadata, pixel_type = read_image(path, level)
    height, width = pixels.shape[:2]
    guard = int(metadata.get("envconv:guard", 0) or 0)
    if layout is None:
        found, guard = detect_layout(width, height, metadata, pixels)
    else:
        found = get_layout(layout)
        if metadata.get("envconv:layout") != found.name:
            guard = 0
    guard >>= level + int(metadata.get("envconv:level", 0) or 0)  # a level's guard is G >> k
    found.size_from_image(width, height, guard)
    if found.name == "latlong" and metadata.get("oiio:sampleborder") and (
        "envconv:layout" not in metadata  # envconv's own files use pixel centres
    ):  # edge-aligned samples, as OpenEXR's ImfEnvmap: see colorflow.resample_edge_aligned
        from .colorflow import resample_edge_aligned

        pixels = resample_edge_aligned(pixels)
    envmap = EnvMap(pixels, found, guard, channels, _content_metadata(metadata), pixel_type)
    return to_working(envmap, input_colorspace, ocio_config)


def _read_multi(template: str, layout: str | None, level: int) -> EnvMap:
    if layout is None:
        first = _part_path(template, "px")
        layout = "cube-faces" if os.path.exists(first) else "paraboloid-split"
    found = get_layout(layout)
    if not found.multi_file:
        raise LayoutError(f"{{face}} in the path needs a multi-file layout, not {found.name}")
    parts = []
    for name in found.face_names:
        parts.append(read_image(_part_path(template, name), level))
    shapes = {p[0].shape for p in parts}
    if len(shapes) != 1:
        raise ImageIOError(f"the {found.name} parts of {template} differ in size or channels")
    pixels, channels, metadata, pixel_type = parts[0]
    guard = int(metadata.get("envconv:guard", 0) or 0)
    if metadata.get("envconv:layout") != found.name:
        guard = 0
    guard >>= level + int(metadata.get("envconv:level", 0) or 0)
    mosaic = np.concatenate([p[0] for p in parts], axis=1)
    found.size_from_image(mosaic.shape[1], mosaic.shape[0], guard)
    return EnvMap(mosaic, found, guard, channels, _content_metadata(metadata), pixel_type)


def mip_levels(path: str | os.PathLike) -> list[tuple[int, int]]:
    """(width, height) of every MIP level of an image file (one entry if it has no chain).

    Multi-file layouts (``{face}`` in the path) report the levels of their first file.
    """
    path = os.fspath(path)
    if "{face}" in path:
        first = _part_path(path, "px")
        path = first if os.path.exists(first) else _part_path(path, "front")
    with _open_input(path) as inp:
        sizes = []
        while inp.seek_subimage(0, len(sizes)):
            spec = inp.spec()
            sizes.append((spec.width, spec.height))
        return sizes


def _part_path(template: str, face: str) -> str:
    return template.replace("{face}", face)


def _content_metadata(metadata: dict[str, Any]) -> dict[str, Any]:
    return {
        k: v
        for k, v in metadata.items()
        if k in _KEEP_NAMES or (not k.startswith(_DROP_PREFIXES) and k not in _DROP_NAMES)
    }
