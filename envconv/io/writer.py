"""Writing environment maps through OpenImageIO: :func:`envconv.io.write` and its helpers.

Every output is written to a temporary file in the destination directory and renamed into place,
so a failure never leaves a partial file, and inputs are never opened for writing. Pixels are
converted from the working space to the output's colour space, range and bit depth by
:func:`envconv.io.encode.encode_output`.
"""

from __future__ import annotations

import logging
import os
from dataclasses import replace

import numpy as np

from ..envmap import EnvMap
from ..errors import ImageIOError
from ..layouts.view import VIEW_TAG, view_text
from .chatter import library_output
from .exr_header import PLACEHOLDER, store_sampleborder
from .files import _first_line, _oiio
from .formats import format_of
from .specs import LevelImage, image_spec, level_image, set_mip_attributes
from .temps import discard as _discard
from .temps import temp_for as _temp_path
from .write_plan import check_write, face_names, output_paths

__all__ = ["write", "write_bytes", "output_paths", "LevelImage"]

log = logging.getLogger(__name__)


def write(
    envmap: EnvMap,
    path: str | os.PathLike,
    bit_depth: str | None = None,
    compression: str | None = None,
    output_colorspace: str | None = None,
    dither: bool = True,
    ocio_config: str | os.PathLike | None = None,
    warnings: list[str] | None = None,
    faces: str | None = None,
) -> list[str]:
    """Write ``envmap`` to ``path`` (one file, or one per face with ``{face}``).

    The pixel type defaults to the source's where the format allows it (see ``FORMATS``).
    Colour is converted from the map's ``oiio:ColorSpace`` to ``output_colorspace`` (default:
    linear Rec.709 for float/half, sRGB for integer types), then clipped and quantized, 8-bit
    with deterministic dither unless ``dither=False``; ``compression`` is checked against
    :data:`envconv.io.formats.COMPRESSIONS` (see :func:`envconv.io.encode.encode_output`).
    Clipping warnings are appended to ``warnings`` when it is a list, else logged.
    Metadata is carried over, plus ``envconv:layout``, ``envconv:size``, ``envconv:guard``,
    ``envconv:version`` and, for unguarded latlong and cube-exr EXRs, OpenEXR's ``envmap``.
    A map with a mip chain (``envmap.levels``) is written as one MIP-mapped file (EXR: tiled
    MIPMAP_LEVELS, ROUND_DOWN, every level down to 1 × 1; TIFF: one directory per level), or
    as one file per level when the path holds ``{level}`` (any format; each file is tagged
    ``envconv:level``). Alpha is written unassociated (never premultiplied). ``faces`` writes a
    ``cube-faces`` map as another program's six skybox files (names and face turns of
    :mod:`envconv.layouts.facesets`). A ``.dds`` or ``.ktx2`` path gets a texture container with every
    level (:mod:`envconv.io.textures`). Returns the paths written.
    """
    from .encode import encode_output

    _check_parts(envmap, os.fspath(path))
    # One file per level (not cells of a mosaic nor parts): encoded a band at a time as written.
    lazy = not envmap.layout.multi_file and not envmap.parts
    encoded = encode_output(envmap, path, output_colorspace, bit_depth, dither, ocio_config,
                            compression, lazy)  # fmt: skip
    _report(encoded.warnings, warnings)
    levels, bit_depth, compression = (
        encoded.levels,
        encoded.plan.pixel_type,
        encoded.plan.compression,
    )
    envmap = replace(envmap, metadata=encoded.metadata, levels=None)
    if encoded.plan.format in ("dds", "ktx2"):
        return [_write_container(envmap, os.fspath(path), encoded.plan.format, levels)]
    per_level = "{level}" in os.fspath(path)
    paths = output_paths(envmap.layout, path, len(levels) if per_level else 1, faces=faces)
    layout = envmap.layout
    cells = [_cells(layout, level, faces) for level in levels]
    names = list(face_names(layout, faces)) if layout.multi_file else [None]
    if per_level:
        jobs = [([cells[k][f]], k, names[f]) for k in range(len(levels)) for f in range(len(names))]
    else:
        jobs = [([cell[f] for cell in cells], None, names[f]) for f in range(len(names))]
    written: list[tuple[str, str]] = []
    try:
        for target, (images, level, face) in zip(paths, jobs, strict=True):
            temp = _temp_path(target)
            written.append((temp, target))
            _write_one(temp, target, images, envmap, face, bit_depth, compression, level)
        for temp, target in written:
            os.replace(temp, target)
        _report(encoded.finish(), warnings)
    finally:
        for temp, _ in written:
            _discard(temp)
    return paths


def _report(messages: list[str], warnings: list[str] | None) -> None:
    """Append ``messages`` to ``warnings``, or log them when it is None."""
    for message in messages:
        if warnings is None:
            log.warning("%s", message)
        else:
            warnings.append(message)


def _check_parts(envmap: EnvMap, path: str) -> None:
    """Refuse, before any work, what a multi-part map cannot be written as."""
    if not envmap.parts:
        return
    fmt = format_of(path)[0]
    names = ", ".join(name for name, _ in envmap.parts)
    if fmt != "openexr":
        raise ImageIOError(f"cannot write {path}: {fmt} holds one image, not the parts {names} "
                           "of the input; pass --part NAME to read one, or write .exr")  # fmt: skip
    if envmap.levels is not None and "{level}" not in path:
        raise ImageIOError(f"cannot write {path}: OpenImageIO writes no MIP levels into a "
                           "multi-part OpenEXR; put {level} in the path for one file per level, "
                           "or pass --part NAME to read one part")  # fmt: skip


def _write_container(envmap: EnvMap, path: str, fmt: str, levels: list[np.ndarray]) -> str:
    """Write a DDS or KTX2 file (:mod:`envconv.io.textures`) through a temporary file."""
    from .. import __version__
    from .textures import encode_texture, texture_images

    output_paths(envmap.layout, path)
    check_write(envmap.layout, path, guard=envmap.guard)
    images, cube = texture_images(envmap.layout, levels, envmap.alpha_index)
    extra = {"envconv:layout": envmap.layout.name}
    if envmap.layout.view:
        extra[VIEW_TAG] = view_text(envmap.layout.view_options)
    if "envconv:roughness" in envmap.metadata:
        extra["envconv:roughness"] = str(envmap.metadata["envconv:roughness"])
    data = encode_texture(fmt, images, cube, envmap.alpha_index is None,
                          f"envconv {__version__}", extra)  # fmt: skip
    return write_bytes(data, path)


def write_bytes(data: bytes, path: str) -> str:
    """Write ``data`` to ``path`` through a temporary file renamed into place; returns the
    path, or raises ImageIOError with one line."""
    temp = _temp_path(path)
    try:
        with open(temp, "wb") as handle:
            handle.write(data)
        os.replace(temp, path)
    except OSError as exc:
        raise ImageIOError(f"cannot write {path}: {exc.strerror or exc}") from None
    finally:
        _discard(temp)
    return path


def _cells(layout, pixels: np.ndarray, faces=None) -> list[np.ndarray]:
    """The per-file images of one level: the whole image, or each cell of a multi-file map
    (turned into the face set's orientation when ``faces`` names one)."""
    if not layout.multi_file:
        return [pixels]
    cw, ch = pixels.shape[1] // layout.columns, pixels.shape[0] // layout.rows
    cells = [
        pixels[c.row * ch : (c.row + 1) * ch, c.col * cw : (c.col + 1) * cw] for c in layout.cells
    ]
    if faces is None:
        return cells
    from ..layouts.facesets import from_envconv

    return from_envconv(faces, cells)


def _write_one(temp, target, images, envmap, face, bit_depth, compression, level=None) -> None:
    """Write one file: ``images`` holds one image, or the levels of a MIP-mapped file; a map
    with parts is written as a multi-part OpenEXR file, one part per entry of ``parts``."""
    fmt = format_of(target)[0]
    if len(images) > 1:
        from ..resample.mips import full_level_count

        full = full_level_count(images[0].shape[1], images[0].shape[0])
        check_write(envmap.layout, target, len(images), full, envmap.guard)
    if envmap.parts:
        writes = _part_writes(target, images[0], envmap, face, bit_depth, compression, level)
    else:
        writes = []
        for k, pixels in enumerate(images):
            image = level_image(target, pixels, envmap, face, bit_depth, compression, level)
            spec = image_spec(image)
            mode = "Create"
            if len(images) > 1:
                set_mip_attributes(spec, fmt)
                mode = (
                    "Create"
                    if k == 0
                    else "AppendMIPLevel"
                    if fmt == "openexr"
                    else "AppendSubimage"
                )
            writes.append((spec, mode, image.data))
    _run_writes(temp, target, writes)
    if fmt == "openexr" and any(
        spec.getattribute(PLACEHOLDER) is not None
        for specs, _, _ in writes
        for spec in (specs if isinstance(specs, list) else [specs])
    ):
        store_sampleborder(temp, target)  # oiio:sampleborder = 0: samples at pixel centres


def _part_writes(target, pixels, envmap, face, bit_depth, compression, level):
    """(spec, mode, data) of every part of a multi-part file: the first opens the file with
    all the parts' specs, as OpenEXR needs them all in its header."""
    writes, start = [], 0
    for name, names in envmap.parts:
        data = pixels[:, :, start : start + len(names)]
        start += len(names)
        image = level_image(target, data, envmap, face, bit_depth, compression, level, names)
        image.attributes.append(("name", name))
        writes.append((image_spec(image), "AppendSubimage", image.data))
    specs = [spec for spec, _, _ in writes]
    writes[0] = (specs, "Create", writes[0][2])
    return writes


def _run_writes(temp, target, writes) -> None:
    """Open ``temp`` and write each (spec or list of specs, mode, data) in turn; one-line
    errors naming ``target``, with what the libraries printed folded in (:mod:`.chatter`)."""
    with library_output(f"cannot write {target}", temp):
        _write_all(temp, target, writes)


def _write_all(temp, target, writes) -> None:
    oiio = _oiio()
    out = oiio.ImageOutput.create(temp)
    if out is None:
        raise ImageIOError(f"cannot write {target}: {_first_line(oiio.geterror())}")
    try:
        for spec, mode, data in writes:
            opened = out.open(temp, spec) if isinstance(spec, list) else out.open(temp, spec, mode)
            if not opened:
                raise ImageIOError(f"cannot write {target}: {_error(out.geterror(), temp, target)}")
            if not _write_pixels(out, data):
                raise ImageIOError(f"cannot write {target}: {_error(out.geterror(), temp, target)}")
    finally:
        ok = out.close()
        message = out.geterror()
        del out  # release (and flush) the file before it is renamed into place
        if not ok:
            raise ImageIOError(f"cannot write {target}: {_error(message, temp, target)}")


def _error(message: str, temp: str, target: str) -> str:
    """The first line of a library's error, naming the target rather than its temp file."""
    return _first_line(message).replace(temp, target)


#: Bytes of pixels handed to OIIO per call. One whole-image ``write_image`` made OIIO's PNG
#: writer hold about nine times the image (docs/memory.md); bands of rows cost one band.
WRITE_BAND_BYTES = 1 << 24


def _write_pixels(out, data) -> bool:
    """Write one image's pixels (H, W, C: an array or an :class:`envconv.io.encode.LazyLevel`)
    to the open ``out`` in bands of rows (scanline files) or of rows of tiles (tiled files);
    False on a write error (``out.geterror()``).

    Tiled files (MIP levels) go through ``write_tiles``, never ``write_image``: OpenImageIO's
    ``write_image`` hands the tiles of a tiled file to its thread pool and, when a write fails
    (a full disk: ENOSPC, EFBIG), waits forever for a task that has given up, with SIGINT
    ignored. ``write_tiles`` writes in this thread and returns False.
    """
    spec = out.spec()
    height = data.shape[0]
    lazy = hasattr(data, "rows")  # an encode.LazyLevel: encoded here, band by band
    rows = max(1, WRITE_BAND_BYTES // max(1, data.shape[1] * data.shape[2] * data.itemsize))
    rows = data.band_rows if lazy else rows
    if spec.tile_width:
        rows = max(spec.tile_height, rows // spec.tile_height * spec.tile_height)
    for y0 in range(0, height, rows):
        band = data.rows(y0, min(height, y0 + rows)) if lazy else data[y0 : y0 + rows]
        y1 = spec.y + y0 + band.shape[0]
        if spec.tile_width:
            done = out.write_tiles(spec.x, spec.x + spec.width, spec.y + y0, y1, spec.z,
                                   spec.z + max(spec.depth, 1), band)  # fmt: skip
        else:
            done = out.write_scanlines(spec.y + y0, y1, spec.z, band)
        if not done:
            return False
    return True
