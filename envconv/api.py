"""File-level operations that the CLI, the pipeline and batch jobs share."""

from __future__ import annotations

import logging
import os
from typing import Any

from . import io
from .resample import preload_kernels
from .sourcemap import convert_source

__all__ = ["convert_file", "plan_convert"]

log = logging.getLogger(__name__)


def convert_file(
    input_path: str | os.PathLike,
    output_path: str | os.PathLike,
    read: dict[str, Any] | None = None,
    resample: dict[str, Any] | None = None,
    write: dict[str, Any] | None = None,
    color: dict[str, Any] | None = None,
    warnings: list[str] | None = None,
) -> list[str]:
    """Read ``input_path``, resample, write ``output_path``; return the paths written.

    ``read``, ``resample`` and ``write`` are keyword arguments for :func:`envconv.io.read`,
    :func:`envconv.resample.convert` and :func:`envconv.io.write`; ``color`` for
    :func:`envconv.colorflow.prepare_input` (exposure, NaN/Inf, negatives). Reading converts
    the source to scene-linear float32 and writing converts it to the output colour space. The output path is checked against the layout before any
    pixel is read, so a bad ``{face}`` path fails fast. One-line warnings (NaN/Inf, clipping)
    are appended to ``warnings`` when it is a list, else logged at WARNING level.
    """
    from .colorflow import plan_output, prepare_input

    resample, write = dict(resample or {}), dict(write or {})
    to = resample.pop("to")
    io.output_paths(to, output_path)
    # Fail fast on a bad --bit-depth, --compression or --output-colorspace, before reading.
    plan_output(output_path, "float", {}, write.get("output_colorspace"), write.get("bit_depth"),
                write.get("ocio_config"), write.get("compression"))  # fmt: skip
    preload_kernels()  # while a one-shot command's input still decodes on another thread
    source = io.read(input_path, **(read or {}))
    source, notes = prepare_input(source, **(color or {}))
    if warnings is None:
        for note in notes:
            log.warning("%s", note)
    else:
        warnings.extend(notes)
    result = convert_source(source, to, **resample)
    return io.write(result, output_path, **write, warnings=warnings)


def plan_convert(
    input_path: str | os.PathLike,
    output_path: str | os.PathLike,
    read: dict[str, Any] | None = None,
    resample: dict[str, Any] | None = None,
    write: dict[str, Any] | None = None,
    color: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """What :func:`convert_file` would write, from the input's header alone (no pixels read).

    Returns a dict: ``files``, ``layout``, ``size`` (N), ``guard``, ``width`` × ``height`` (one
    file), ``levels``, ``channels``, ``bit_depth``, ``compression`` (None: format default),
    ``input_colorspace``, ``working_colorspace`` and ``output_colorspace`` (OCIO names).
    """
    from .colorflow import WORKING_COLORSPACE, input_colorspace_of, plan_output
    from .pipeline import Pipeline, Read, Resample, Write

    read, write, color = dict(read or {}), dict(write or {}), dict(color or {})
    resample = dict(resample or {})
    output = Pipeline([Read(input_path, **read), Resample(**resample), Write(output_path)]).plan()[0]
    first = _first_file(os.fspath(input_path), read.get("layout"))
    _, _, channels, metadata = io.read_header(first, int(read.get("level", 0) or 0), read.get("part"))
    pixel_type = io.read_pixel_type(first, read.get("part"))
    config = write.get("ocio_config") or read.get("ocio_config")
    source = input_colorspace_of(metadata, pixel_type, read.get("input_colorspace"), config)
    working = input_colorspace_of({}, "float", WORKING_COLORSPACE, config)
    plan = plan_output(output_path, pixel_type, {"oiio:ColorSpace": working},
                       write.get("output_colorspace"), write.get("bit_depth"), config,
                       write.get("compression"))  # fmt: skip
    channels = list(channels)
    if resample.get("alpha") and not any(c.upper() == "A" or c.lower() == "alpha" for c in channels):
        channels.append("A")
    max_channels = io.FORMATS[os.path.splitext(os.fspath(output_path))[1].lower()][3]
    channels = ["R", "G", "B"] if plan.format == "hdr" else channels[:max_channels]
    return {
        "files": list(output.files), "layout": output.layout, "size": output.size,
        "guard": output.guard, "width": output.width, "height": output.height,
        "levels": output.levels, "channels": channels, "bit_depth": plan.pixel_type,
        "compression": plan.compression, "input_colorspace": source,
        "working_colorspace": working, "output_colorspace": plan.colorspace,
    }  # fmt: skip


def _first_file(path: str, layout: str | None) -> str:
    """The file whose header stands for a (possibly ``{face}``) input path."""
    if "{face}" not in path:
        return path
    from .layouts import get_layout

    names = get_layout(layout).face_names if layout else ("px", "front")
    for name in names:
        if os.path.exists(path.replace("{face}", name)):
            return path.replace("{face}", name)
    return path.replace("{face}", names[0])
