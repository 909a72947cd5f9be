"""Reading and writing environment maps through OpenImageIO. The only module that touches files.

Formats: OpenEXR (half or float), Radiance HDR, TIFF, PNG and JPEG, chosen by the file
extension. Pixels are always float32 in memory. Until colour management lands, integer files
are read and written as OpenImageIO gives them: code values scaled to [0, 1], with no transfer
function applied, and float data written to an integer format is clamped to [0, 1].

Multi-file layouts (cube-faces, paraboloid-split) name their parts with ``{face}`` in the path:
px nx py ny pz nz, or front back.

Every output is written to a temporary file in the destination directory and renamed into place,
so a failure never leaves a partial file, and inputs are never opened for writing.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Any

import numpy as np

from .detect import detect_layout
from .envmap import EnvMap
from .errors import ImageIOError, LayoutError
from .layouts import get_layout

__all__ = ["read", "write", "read_image", "output_paths", "FORMATS"]

log = logging.getLogger(__name__)

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

# Metadata that describes a file's encoding rather than its content; never copied to an output.
_DROP_PREFIXES = ("oiio:", "envconv:", "openexr:", "tiff:", "png:", "jpeg:", "exif:", "hdr:")
_DROP_NAMES = {"envmap", "compression", "planarconfig", "Orientation", "XResolution",
               "YResolution", "ResolutionUnit", "PixelAspectRatio", "screenWindowCenter",
               "screenWindowWidth", "tile_width", "tile_height", "Software"}  # fmt: skip
_KEEP_NAMES = {"oiio:ColorSpace"}


def _oiio():
    import OpenImageIO

    return OpenImageIO


def read_image(path: str | os.PathLike, level: int = 0):
    """Read one image file as float32 (H, W, C).

    Returns
    -------
    pixels, channel names, metadata dict, pixel type (``half``/``float``/``uint8``/``uint16``)
    """
    oiio = _oiio()
    path = os.fspath(path)
    if not os.path.exists(path):
        raise ImageIOError(f"input file not found: {path}")
    if os.path.isdir(path):
        raise ImageIOError(f"input is a directory, not an image: {path}")
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise ImageIOError(f"cannot read {path}: {_first_line(oiio.geterror())}")
    try:
        if level and not inp.seek_subimage(0, level):
            raise ImageIOError(f"cannot read {path}: it has no MIP level {level}")
        spec = inp.spec()
        pixels = inp.read_image(0, level, 0, spec.nchannels, oiio.FLOAT)
        if pixels is None or inp.has_error:
            raise ImageIOError(f"cannot read {path}: {_first_line(inp.geterror())}")
        metadata = {attr.name: attr.value for attr in spec.extra_attribs}
        channels = tuple(spec.channelnames)
        pixel_type = str(spec.format)
    finally:
        inp.close()
    pixels = np.asarray(pixels, np.float32).reshape(spec.height, spec.width, spec.nchannels)
    return np.ascontiguousarray(pixels), channels, metadata, pixel_type


def _first_line(message: str) -> str:
    message = (message or "unknown error").strip()
    return message.splitlines()[0] if message else "unknown error"


def read(path: str | os.PathLike, layout: str | None = None, level: int = 0) -> EnvMap:
    """Read an environment map.

    Parameters
    ----------
    path : str or path
        Image file. Multi-file layouts use ``{face}`` in the path.
    layout : str, optional
        Layout name (``--from``); detected from metadata or the aspect ratio when omitted.
    level : int
        MIP level to read (0, the full resolution, by default).
    """
    path = os.fspath(path)
    if "{face}" in path:
        return _read_multi(path, layout, level)
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
    if guard:
        guard = guard // (1 << level) if level else guard
    found.size_from_image(width, height, guard)
    return EnvMap(pixels, found, guard, channels, _content_metadata(metadata), pixel_type)


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
    mosaic = np.concatenate([p[0] for p in parts], axis=1)
    found.size_from_image(mosaic.shape[1], mosaic.shape[0], guard)
    return EnvMap(mosaic, found, guard, channels, _content_metadata(metadata), pixel_type)


def _part_path(template: str, face: str) -> str:
    return template.replace("{face}", face)


def _content_metadata(metadata: dict[str, Any]) -> dict[str, Any]:
    return {
        k: v
        for k, v in metadata.items()
        if k in _KEEP_NAMES or (not k.startswith(_DROP_PREFIXES) and k not in _DROP_NAMES)
    }


def output_paths(envmap_layout, path: str | os.PathLike) -> list[str]:
    """Files that writing a map of this layout to ``path`` produces."""
    layout = get_layout(envmap_layout)
    path = os.fspath(path)
    if layout.multi_file:
        if "{face}" not in path:
            raise LayoutError(
                f"layout {layout.name} writes {len(layout.face_names)} files; "
                "put {face} in the output path, e.g. sky_{face}.exr"
            )
        return [_part_path(path, name) for name in layout.face_names]
    if "{face}" in path:
        raise LayoutError(
            f"{{face}} in the output path needs a multi-file layout, not {layout.name}"
        )
    return [path]


def _format_of(path: str):
    ext = Path(path).suffix.lower()
    if ext not in FORMATS:
        known = " ".join(sorted(FORMATS))
        raise ImageIOError(
            f"cannot write {path}: unknown extension {ext or '(none)'} (known: {known})"
        )
    return FORMATS[ext]


def _choose_type(path: str, pixel_type: str, bit_depth: str | None) -> str:
    fmt, allowed, default, _ = _format_of(path)
    if bit_depth is not None:
        if bit_depth not in allowed:
            raise ImageIOError(f"{fmt} cannot store {bit_depth}; it stores {', '.join(allowed)}")
        return bit_depth
    if pixel_type in allowed:
        return pixel_type
    if default is not None:
        return default
    return "half" if pixel_type == "uint8" else "float"


def write(
    envmap: EnvMap,
    path: str | os.PathLike,
    bit_depth: str | None = None,
    compression: str | None = None,
) -> list[str]:
    """Write ``envmap`` to ``path`` (one file, or one per face with ``{face}``).

    The pixel type defaults to the source's where the format allows it (see ``FORMATS``).
    Metadata is carried over, plus ``envconv:layout``, ``envconv:size``, ``envconv:guard``,
    ``envconv:version`` and, for unguarded latlong and cube-exr EXRs, OpenEXR's ``envmap``.
    Returns the paths written.
    """
    paths = output_paths(envmap.layout, path)
    layout = envmap.layout
    if layout.multi_file:
        cw, ch = layout.cell_size(envmap.size, envmap.guard)
        images = []
        for cell in layout.cells:
            x0, y0 = cell.col * cw, cell.row * ch
            images.append(envmap.pixels[y0 : y0 + ch, x0 : x0 + cw])
        faces = list(layout.face_names)
    else:
        images, faces = [envmap.pixels], [None]
    temps: list[tuple[str, str]] = []
    try:
        for target, pixels, face in zip(paths, images, faces, strict=True):
            temp = _temp_path(target)
            temps.append((temp, target))
            _write_one(temp, target, pixels, envmap, face, bit_depth, compression)
        for temp, target in temps:
            os.replace(temp, target)
    finally:
        for temp, _ in temps:
            if os.path.exists(temp):
                os.remove(temp)
    return paths


def _temp_path(target: str) -> str:
    directory, name = os.path.split(os.path.abspath(target))
    if not os.path.isdir(directory):
        raise ImageIOError(f"cannot write {target}: directory {directory} does not exist")
    stem, ext = os.path.splitext(name)
    return os.path.join(directory, f".{stem}.envconv-{os.getpid()}.tmp{ext}")


def _write_one(temp, target, pixels, envmap: EnvMap, face, bit_depth, compression) -> None:
    oiio = _oiio()
    fmt, _, _, max_channels = _format_of(target)
    pixel_type = _choose_type(target, envmap.pixel_type, bit_depth)
    channels = list(envmap.channels)
    if max_channels is not None and len(channels) > max_channels:
        log.warning(
            "%s stores at most %d channels; writing %s",
            fmt,
            max_channels,
            ",".join(channels[:max_channels]),
        )
        pixels = pixels[:, :, :max_channels]
        channels = channels[:max_channels]
    if fmt == "hdr" and len(channels) != 3:
        pixels = np.repeat(pixels[:, :, :1], 3, axis=2)
        channels = ["R", "G", "B"]
    height, width, nch = pixels.shape
    spec = oiio.ImageSpec(width, height, nch, getattr(oiio, pixel_type.upper()))
    spec.channelnames = tuple(channels)
    if envmap.alpha_index is not None and envmap.alpha_index < nch:
        spec.alpha_channel = envmap.alpha_index
    for name, value in envmap.metadata.items():
        _set_attribute(spec, name, value)
    _set_envconv_tags(spec, envmap, fmt, face)
    if compression is not None:
        spec.attribute("compression", compression)
    out = oiio.ImageOutput.create(temp)
    if out is None:
        raise ImageIOError(f"cannot write {target}: {_first_line(oiio.geterror())}")
    try:
        if not out.open(temp, spec):
            raise ImageIOError(f"cannot write {target}: {_first_line(out.geterror())}")
        data = np.ascontiguousarray(pixels, np.float32)
        if not out.write_image(data):
            raise ImageIOError(f"cannot write {target}: {_first_line(out.geterror())}")
    finally:
        if not out.close():
            raise ImageIOError(f"cannot write {target}: {_first_line(out.geterror())}")


def _set_envconv_tags(spec, envmap: EnvMap, fmt: str, face: str | None) -> None:
    from . import __version__

    spec.attribute("envconv:layout", envmap.layout.name)
    spec.attribute("envconv:size", int(envmap.size))
    spec.attribute("envconv:guard", int(envmap.guard))
    spec.attribute("envconv:version", __version__)
    spec.attribute("Software", f"envconv {__version__}")
    if face is not None:
        spec.attribute("envconv:face", face)
    if fmt == "openexr" and envmap.guard == 0:
        if envmap.layout.name == "latlong":
            spec.attribute("envmap", "latlong")
        elif envmap.layout.name == "cube-exr":
            spec.attribute("envmap", "cube")


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
