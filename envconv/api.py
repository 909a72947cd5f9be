"""File-level operations that the CLI, the pipeline and batch jobs share."""

from __future__ import annotations

import logging
import os
from typing import Any

from . import io
from .errors import UsageError
from .resample import convert

__all__ = ["convert_file", "plan_convert", "route_face_sets"]

log = logging.getLogger(__name__)


def convert_file(
    input_path: str | os.PathLike,
    output_path: str | os.PathLike,
    read: dict[str, Any] | None = None,
    resample: dict[str, Any] | None = None,
    write: dict[str, Any] | None = None,
    color: dict[str, Any] | None = None,
    warnings: list[str] | None = None,
    preview: str | os.PathLike | None = None,
) -> list[str]:
    """Read ``input_path``, resample, write ``output_path``; return the paths written.

    ``preview``: also write a tone-mapped 8-bit picture of the result there (automatic
    exposure, ACES SDR view: :func:`envconv.preview.preview_picture`); it is listed last.

    ``read``, ``resample`` and ``write`` are keyword arguments for :func:`envconv.io.read`,
    :func:`envconv.resample.convert` and :func:`envconv.io.write`; ``color`` for
    :func:`envconv.prepare.prepare_input` (exposure, NaN/Inf, negatives). Reading converts
    the source to scene-linear float32 and writing converts it to the output colour space. The output path is checked against the layout before any
    pixel is read, so a bad ``{face}`` path fails fast. One-line warnings (NaN/Inf, clipping)
    are appended to ``warnings`` when it is a list, else logged at WARNING level.
    """
    from .io.encode import plan_output
    from .prepare import prepare_input

    read, resample, write = dict(read or {}), dict(resample or {}), dict(write or {})
    route_face_sets(input_path, read, resample, write)
    to = resample.pop("to")
    outputs = io.output_paths(to, output_path, faces=write.get("faces"))
    _refuse_writing_onto_inputs(input_path, read.get("layout"), read.get("faces"), outputs)
    if preview is not None and os.path.abspath(preview) in (os.path.abspath(output_path),
                                                            os.path.abspath(input_path)):  # fmt: skip
        raise UsageError(f"--preview {preview} would overwrite the input or the output")
    # Fail fast on a bad --bit-depth, --compression or --output-colorspace, before reading.
    plan_output(output_path, "float", {}, write.get("output_colorspace"), write.get("bit_depth"),
                write.get("ocio_config"), write.get("compression"))  # fmt: skip
    source = io.read(input_path, **read)
    source, notes = prepare_input(source, **(color or {}))
    if warnings is None:
        for note in notes:
            log.warning("%s", note)
    else:
        warnings.extend(notes)
    result = convert(source, to, **resample)
    paths = io.write(result, output_path, **write, warnings=warnings)
    if preview is not None:
        from .io.picture import write_picture
        from .preview import preview_picture

        paths.append(write_picture(preview_picture(result), preview))
    return paths


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
    from .color import WORKING_COLORSPACE, input_colorspace_of
    from .io.encode import plan_output
    from .pipeline import Pipeline, Read, Resample, Write

    read, write, color = dict(read or {}), dict(write or {}), dict(color or {})
    resample = dict(resample or {})
    route_face_sets(input_path, read, resample, write)
    faces = {"faces": write["faces"]} if write.get("faces") else {}
    output = Pipeline([Read(input_path, **read), Resample(**resample),
                       Write(output_path, **faces)]).plan()[0]  # fmt: skip
    first = _first_file(os.fspath(input_path), read.get("layout"), read.get("faces"))
    level, part = int(read.get("level", 0) or 0), read.get("part")
    _, _, channels, metadata = io.read_header(first, level, part)
    pixel_type = io.read_pixel_type(first, part)
    config = write.get("ocio_config") or read.get("ocio_config")
    source = input_colorspace_of(metadata, pixel_type, read.get("input_colorspace"), config)
    working = input_colorspace_of({}, "float", WORKING_COLORSPACE, config)
    plan = plan_output(output_path, pixel_type, {"oiio:ColorSpace": working},
                       write.get("output_colorspace"), write.get("bit_depth"), config,
                       write.get("compression"))  # fmt: skip
    channels = list(channels)
    if resample.get("alpha") and not any(c.upper() == "A" or c.lower() == "alpha" for c in channels):
        channels.append("A")
    max_channels = io.WRITE_FORMATS[os.path.splitext(os.fspath(output_path))[1].lower()][3]
    channels = ["R", "G", "B"] if plan.format == "hdr" else channels[:max_channels]
    return {
        "files": list(output.files), "layout": output.layout, "size": output.size,
        "guard": output.guard, "width": output.width, "height": output.height,
        "levels": output.levels, "channels": channels, "bit_depth": plan.pixel_type,
        "compression": plan.compression, "input_colorspace": source,
        "working_colorspace": working, "output_colorspace": plan.colorspace,
    }  # fmt: skip


def _refuse_writing_onto_inputs(input_path, layout, faces, outputs: list[str]) -> None:
    """UsageError, before any work, when an output file is an input file (the same path, or
    the same file through a link): envconv never writes onto its input."""
    path = os.fspath(input_path)
    if "{face}" in path:
        from .io.face_files import find_face_files

        inputs = find_face_files(path, layout, faces).paths
    else:
        inputs = [path]
    existing = [p for p in inputs if os.path.exists(p)]
    for output in outputs:
        if not os.path.exists(output):
            continue
        for source in existing:
            if os.path.samefile(output, source):
                raise UsageError(f"{output} is the input {source}; envconv never writes onto its "
                                 "input: choose another output path")  # fmt: skip


def _first_file(path: str, layout: str | None, faces=None) -> str:
    """The file whose header stands for a (possibly ``{face}``) input path."""
    if "{face}" not in path:
        return path
    from .io.face_files import find_face_files

    return find_face_files(path, layout, faces).paths[0]


def route_face_sets(input_path, read: dict, resample: dict, write: dict) -> None:
    """Move a convention that names a skybox face set from resampling to reading or writing.

    ``in_convention`` goes to ``read["faces"]`` when the input is a ``{face}`` path of cube
    faces, and ``out_convention`` to ``write["faces"]`` when the output layout is cube-faces:
    a face set names files and turns faces (:mod:`envconv.facesets`), which only reading and
    writing can do. Other conventions (``unreal`` on a lat-long, …) stay with resampling.
    The dicts are changed in place.
    """
    from .facesets import is_face_set
    from .layouts import get_layout

    cin, cout = resample.get("in_convention"), resample.get("out_convention")
    if (is_face_set(cin) and "{face}" in os.fspath(input_path) and not read.get("faces")
            and read.get("layout") in (None, "cube-faces")):  # fmt: skip
        read["faces"] = resample.pop("in_convention")
    if (is_face_set(cout) and resample.get("to") is not None and not write.get("faces")
            and get_layout(resample["to"]).name == "cube-faces"):  # fmt: skip
        write["faces"] = resample.pop("out_convention")
