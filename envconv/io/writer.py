"""Writing environment maps through OpenImageIO: :func:`envconv.io.write` and its helpers.

Every output is written to a temporary file in the destination directory and renamed into place
(:mod:`envconv.io.output`, every result checked), the files of one map (faces, levels) all at
once (:mod:`envconv.io.sets`), so a failure never leaves a partial file or a mixed set, and
inputs are never opened for writing. Pixels are converted from the working space to the
output's colour space, range and bit depth by :func:`envconv.io.encode.encode_output`.
"""

from __future__ import annotations

import logging
import os
from dataclasses import replace

import numpy as np

from ..envmap import EnvMap
from ..errors import ImageIOError
from ..layouts.view import VIEW_TAG, view_text
from .exr_header import PLACEHOLDER, store_sampleborder
from .face_files import has_placeholder
from .formats import format_of
from .output import write_bytes, write_files, write_images
from .specs import LevelImage, image_spec, level_image, set_mip_attributes
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
    level (:mod:`envconv.io.textures`). ``{face}`` and ``{level}`` may sit in folder names too;
    a doubled brace stands for one (``a{{level}}.exr`` is the file ``a{level}.exr``). The files
    replace older ones all at once (:mod:`envconv.io.sets`). Returns the paths written.
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
        (target,) = output_paths(envmap.layout, path)
        return [_write_container(envmap, target, encoded.plan.format, levels)]
    per_level = has_placeholder(os.fspath(path), "level")
    paths = output_paths(envmap.layout, path, len(levels) if per_level else 1, faces=faces)
    layout = envmap.layout
    cells = [_cells(layout, level, faces) for level in levels]
    names = list(face_names(layout, faces)) if layout.multi_file else [None]
    if per_level:
        jobs = [([cells[k][f]], k, names[f]) for k in range(len(levels)) for f in range(len(names))]
    else:
        jobs = [([cell[f] for cell in cells], None, names[f]) for f in range(len(names))]

    def write_file(temp: str, target: str, index: int) -> None:
        images, level, face = jobs[index]
        _write_one(temp, target, images, envmap, face, bit_depth, compression, level)

    write_files(paths, write_file)  # all or none, renamed together (envconv.io.sets)
    _report(encoded.finish(), warnings)
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
    if envmap.levels is not None and not has_placeholder(path, "level"):
        raise ImageIOError(f"cannot write {path}: OpenImageIO writes no MIP levels into a "
                           "multi-part OpenEXR; put {level} in the path for one file per level, "
                           "or pass --part NAME to read one part")  # fmt: skip


def _write_container(envmap: EnvMap, path: str, fmt: str, levels: list[np.ndarray]) -> str:
    """Write a DDS or KTX2 file (:mod:`envconv.io.textures`) through a temporary file."""
    from .. import __version__
    from .textures import encode_texture, texture_images

    check_write(envmap.layout, path, guard=envmap.guard)
    images, cube = texture_images(envmap.layout, levels, envmap.alpha_index)
    extra = {"envconv:layout": envmap.layout.name, "envconv:size": str(envmap.size),
             "envconv:guard": str(envmap.guard),
             "envconv:channels": "RGB" if envmap.alpha_index is None else "RGBA"}  # fmt: skip
    if envmap.layout.view:
        extra[VIEW_TAG] = view_text(envmap.layout.view_options)
    if "envconv:roughness" in envmap.metadata:
        extra["envconv:roughness"] = str(envmap.metadata["envconv:roughness"])
    data = encode_texture(fmt, images, cube, envmap.alpha_index is None,
                          f"envconv {__version__}", extra)  # fmt: skip
    return write_bytes(data, path)


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
    write_images(temp, target, writes)
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
