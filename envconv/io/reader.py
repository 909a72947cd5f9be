"""Reading and writing environment maps: the file side of envconv.

Formats: OpenEXR (half or float), Radiance HDR, TIFF, PNG and JPEG, chosen by the file
extension. Pixels are always float32 in memory, in scene-linear Rec.709: :func:`read` and
:func:`write` convert colour, range and bit depth through :mod:`envconv.color.ocio` and :mod:`envconv.io.encode`.

Multi-file layouts (cube-faces, paraboloid-split) name their parts with ``{face}`` in the path:
px nx py ny pz nz, or front back. ``faces=`` names another program's skybox files and face
orientations (Quake's ft bk lf rt up dn, Unity's Front …: :mod:`envconv.layouts.facesets`); reading
finds the set from the files that exist when it is not given (:mod:`envconv.io.face_files`).

This module reads maps (files through :mod:`envconv.io.files`); writing lives in
:mod:`envconv.io.writer` (every output goes to a temporary file renamed into place, so a failure
never leaves a partial file, and inputs are never opened for writing) and is re-exported here.
"""

from __future__ import annotations

import logging
import os
from typing import Any

import numpy as np

from ..envmap import EnvMap, alpha_channel
from ..errors import ImageIOError, LayoutError
from ..layouts import get_layout
from ..layouts.detect import place_image
from ..layouts.grids import to_centres
from .files import FileHeader, _open_input, read_file, read_file_header, read_image, read_pixel_type

__all__ = ["read", "read_unplaced", "read_image", "read_header", "read_pixel_type", "mip_levels",
           "resample_edge_aligned"]  # fmt: skip

log = logging.getLogger(__name__)

# Metadata that describes a file's encoding rather than its content; never copied to an output.
_DROP_PREFIXES = ("oiio:", "envconv:", "openexr:", "tiff:", "png:", "jpeg:", "exif:", "hdr:")
_DROP_NAMES = {"envmap", "compression", "planarconfig", "Orientation", "XResolution",
               "YResolution", "ResolutionUnit", "PixelAspectRatio", "screenWindowCenter",
               "screenWindowWidth", "tile_width", "tile_height", "Software", "textureformat",
               "name"}  # fmt: skip
_KEEP_NAMES = {"oiio:ColorSpace", "envconv:grid"}  # the grid: see envconv.layouts.grids


def read(
    path: str | os.PathLike,
    layout: str | None = None,
    level: int = 0,
    input_colorspace: str | None = None,
    ocio_config: str | os.PathLike | None = None,
    part: str | None = None,
    faces: str | None = None,
    threads: int | None = None,
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
    part : str, optional
        Part of a multi-part file to read alone (its name, or its index); default every part
        that is an image of the first part's windows (see :mod:`envconv.io.files`).
    faces : str, optional
        Face set of a ``{face}`` path of six skybox files (``quake``, ``unity-6sided``,
        ``threejs``, ``godot``, ``unreal``, ``envconv``; see :mod:`envconv.layouts.facesets`). Each
        file is turned into envconv's face, so the result is an ordinary ``cube-faces`` map.
        Default: found from the file names; several matching sets are a LayoutError.
    threads : int, optional
        Threads of the native core for this call (layout detection, an edge-aligned lat-long
        resampled onto pixel centres); default: the process setting
        (:func:`envconv.resample.kernels.set_threads`). OpenImageIO's and OpenEXR's own
        decoding threads are process settings: their Python APIs take no count per file.

    The map is the file's display window (:mod:`envconv.io.files`). Where the data window
    leaves holes, every channel is 0 there, an alpha channel ``A`` (1 elsewhere) is added
    when the file has none, and ``EnvMap.valid`` marks them. Pixels are converted to linear
    Rec.709 by :func:`envconv.color.ocio.to_working`. A lat-long stored with edge-aligned
    samples (``oiio:sampleborder``, as OpenEXR envmaps written by other tools) is resampled
    onto pixel centres (:func:`resample_edge_aligned`).
    """
    from ..resample.kernels import threads_for

    with threads_for(threads):
        return _read(path, layout, level, input_colorspace, ocio_config, part, faces)


def _read(path, layout, level, input_colorspace, ocio_config, part, faces) -> EnvMap:
    """:func:`read` with the kernel threads chosen."""
    from ..color.ocio import to_working

    path = os.fspath(path)
    if "{face}" in path:
        return to_working(_read_multi(path, layout, level, part, faces), input_colorspace,
                          ocio_config)  # fmt: skip
    if faces is not None:
        raise LayoutError(f"a face set ({faces}) needs {{face}} in the path, e.g. sky_{{face}}.hdr")
    if layout is not None and get_layout(layout).multi_file:
        raise LayoutError(f"layout {layout} is stored as several files; put {{face}} in the path")
    _check_memory(path, level, part)
    image = read_file(path, level, part)
    header = image.header
    pixels, channels, parts = _with_alpha(image.pixels, header, image.valid)
    metadata, valid = header.metadata, image.valid
    found, guard, _ = place_image(header.width, header.height, metadata, layout, pixels, level)
    if (
        found.name == "latlong"
        and metadata.get("oiio:sampleborder")
        and (
            "envconv:layout" not in metadata  # envconv's own files use pixel centres
        )
    ):  # edge-aligned samples, as OpenEXR's ImfEnvmap: see resample_edge_aligned
        pixels = resample_edge_aligned(pixels)
        valid = None if valid is None else resample_edge_aligned(valid[:, :, None])[:, :, 0]
    envmap = EnvMap(pixels, found, guard, channels, _content_metadata(metadata),
                    header.pixel_type, valid=valid, parts=parts)  # fmt: skip
    return to_working(envmap, input_colorspace, ocio_config)


def _check_memory(path: str, level: int, part, files: int = 1) -> None:
    """Refuse, from the header and before any pixel is read, an image (or ``files`` images of
    one size, placed side by side) whose reading cannot fit in memory (:mod:`envconv.engine.memory`)."""
    from ..engine import memory

    header = read_file_header(path, level, part)
    holes = header.holes
    channels = len(header.channels) + int(holes and alpha_channel(header.channels) is None)
    need = memory.estimate_read(header.width, header.height, channels, header.pixel_type, holes)
    if files > 1:  # every file's image, then the mosaic they are joined into
        need = 2 * files * (need - memory.SLACK) + memory.SLACK
    memory.check(
        need, f"reading {path}", 0, "read a lower --level or a smaller file, or free memory"
    )


def _with_alpha(pixels: np.ndarray, header: FileHeader, valid: np.ndarray | None):
    """(pixels, channels, parts) of a file's image, with an alpha channel ``A`` (the first
    part's) holding ``valid`` when the image has holes and no alpha."""
    channels = header.channels
    parts = header.part_channels if len(header.chosen) > 1 else ()
    if valid is None or alpha_channel(channels) is not None:
        return pixels, channels, parts
    at = len(header.first.channels)
    pixels = np.concatenate([pixels[:, :, :at], valid[:, :, None], pixels[:, :, at:]], axis=2)
    if parts:
        parts = ((parts[0][0], (*parts[0][1], "A")), *parts[1:])
    return pixels, (*channels[:at], "A", *channels[at:]), parts


def read_unplaced(path: str | os.PathLike, level: int = 0, part: str | None = None):
    """(pixels, channels) of an image file as :func:`read` gives a map's, before any layout
    is placed (display window; holes 0, with an ``A`` added): for images that fit none."""
    image = read_file(os.fspath(path), level, part)
    pixels, channels, _ = _with_alpha(image.pixels, image.header, image.valid)
    return pixels, channels


def read_header(path: str | os.PathLike, level: int = 0, part: str | None = None):
    """Width, height, channels and metadata of the map :func:`read` would give (display
    window; an ``A`` added where the data window leaves holes), from the header alone."""
    header = read_file_header(path, level, part)
    channels = header.channels
    if header.holes and alpha_channel(channels) is None:
        at = len(header.first.channels)
        channels = (*channels[:at], "A", *channels[at:])
    return header.width, header.height, channels, header.metadata


def _read_multi(
    template: str, layout: str | None, level: int, part: str | None, faces=None
) -> EnvMap:
    """The parts of ``template`` side by side in face order, each cube face turned from its
    face set's orientation into envconv's; holes (and an ``A``) as in :func:`read`."""
    from .face_files import find_face_files
    from .sets import read_settled

    files = None  # the set found by the last find()

    def find() -> list[str]:
        nonlocal files
        files = find_face_files(template, layout, faces)
        return files.paths

    def read_all(paths: list[str]) -> list:
        _check_memory(paths[0], level, part, len(paths))
        return [read_file(path, level, part) for path in paths]

    images = read_settled(find, read_all)  # never a set half replaced (envconv.io.sets)
    found = get_layout(files.layout)
    holes = any(image.valid is not None for image in images)
    cells = []
    for image in images:
        valid = image.valid
        if holes and valid is None:
            valid = np.ones(image.pixels.shape[:2], np.float32)
        cells.append((*_with_alpha(image.pixels, image.header, valid), valid))
    if len({c[0].shape for c in cells}) != 1 or len({c[1] for c in cells}) != 1:
        raise ImageIOError(f"the {found.name} parts of {template} differ in size or channels")
    pixels = [c[0] for c in cells]
    valids = [c[3] for c in cells]
    if files.face_set is not None:
        from ..layouts.facesets import to_envconv

        pixels = to_envconv(files.face_set, pixels)
        if holes:
            valids = [
                v[:, :, 0] for v in to_envconv(files.face_set, [v[:, :, None] for v in valids])
            ]
    header = images[0].header
    mosaic = np.concatenate(pixels, axis=1)
    valid = np.concatenate(valids, axis=1) if holes else None
    _, guard, _ = place_image(mosaic.shape[1], mosaic.shape[0], header.metadata, found, level=level)
    return EnvMap(mosaic, found, guard, cells[0][1], _content_metadata(header.metadata),
                  header.pixel_type, valid=valid, parts=cells[0][2])  # fmt: skip


def mip_levels(path: str | os.PathLike, part: str | None = None) -> list[tuple[int, int]]:
    """(width, height) of the display window of every MIP level of an image file (of its
    first part, or ``part``); one entry if it has no chain.

    Multi-file layouts (``{face}`` in the path) report the levels of their first file.
    """
    from .face_files import first_file

    path = first_file(path)
    header = read_file_header(path, 0, part)
    if header.format in ("dds", "ktx2"):  # envconv's own reader (envconv.io.textures)
        from .textures import texture_info, texture_size

        info = texture_info(path)
        return [texture_size(info, k) for k in range(info.levels)]
    index = header.chosen[0]
    with _open_input(path) as inp:
        sizes: list[tuple[int, int]] = []
        while inp.seek_subimage(index, len(sizes)):
            spec = inp.spec()
            sizes.append((spec.full_width, spec.full_height))
        return sizes


def _content_metadata(metadata: dict[str, Any]) -> dict[str, Any]:
    return {
        k: v
        for k, v in metadata.items()
        if k in _KEEP_NAMES or (not k.startswith(_DROP_PREFIXES) and k not in _DROP_NAMES)
    }


def resample_edge_aligned(pixels: np.ndarray) -> np.ndarray:
    """Resample an image with edge-aligned samples onto the pixel-centre grid, same size.

    In a file with ``oiio:sampleborder`` = 1 (what OIIO reports for every OpenEXR with an
    ``envmap`` attribute, after OpenEXR's ``ImfEnvmap``), sample (i, j) of a W × H image sits
    at u = i / (W − 1), v = j / (H − 1): the first and last columns both lie on the seam
    (lon = ±π) and the first and last rows on the poles. envconv's pixel (i, j) has its
    centre at ((i + 0.5) / W, (j + 0.5) / H), i.e. at file position (i + 0.5)(W − 1)/W.
    Each output value is the linear interpolation of the two nearest file samples, rows and
    columns separably (exact for constants and for functions linear in u and v). An axis of
    one sample is left as it is. This is :func:`envconv.layouts.grids.to_centres` of the
    ``edges`` grid.

    Parameters
    ----------
    pixels : ndarray, shape (H, W, C)

    Returns
    -------
    ndarray of float32, shape (H, W, C)

    Examples
    --------
    >>> px = np.arange(3, dtype=np.float32).reshape(1, 3, 1) * np.ones((2, 1, 1), np.float32)
    >>> [round(float(x), 4) for x in resample_edge_aligned(px)[0, :, 0]]  # u = 1/6, 1/2, 5/6
    [0.3333, 1.0, 1.6667]
    """
    return to_centres(pixels, "edges")
