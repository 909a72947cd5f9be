"""File-level operations that the CLI, the pipeline and batch jobs share."""

from __future__ import annotations

import logging
import os
from typing import Any

from .. import io

__all__ = ["convert_file", "convert_record", "convert_pipeline", "plan_convert", "route_face_sets"]

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

    This is the pipeline ``Read → Resample → Write`` (:func:`convert_pipeline`), run by the
    engine that runs chains, graph files and batches, so it follows their rules: the output
    policy is checked before any work (no output onto the input, no two outputs on one path,
    ``write["no_clobber"]`` refuses an existing output; :mod:`envconv.engine.outputs`), missing output
    directories are created, and a bad ``{face}`` path, bit depth, compression or colour space
    fails before any pixel is read.

    ``read``, ``resample`` and ``write`` are keyword arguments for :func:`envconv.io.read`,
    :func:`envconv.resample.convert.convert` and :func:`envconv.io.write` (plus ``no_clobber``);
    ``color`` for :func:`envconv.color.prepare.prepare_input` (exposure, NaN/Inf, negatives).
    Reading converts the source to scene-linear float32 and writing converts it to the output
    colour space. ``preview``: also write a tone-mapped 8-bit picture of the result there
    (:func:`envconv.views.preview.preview_picture`); it is listed last. One-line warnings (NaN/Inf,
    clipping) are appended to ``warnings`` when it is a list, else logged at WARNING level.
    """
    pipeline = convert_pipeline(input_path, output_path, read, resample, write, color, preview)
    written: list[str] = []
    pipeline.run(keep=False, written=written, warnings=warnings)
    return written


def convert_record(input_path, output_path, read=None, resample=None, write=None, color=None,
                   warnings: list[str] | None = None, preview=None,
                   dry_run: bool = False) -> dict[str, Any]:  # fmt: skip
    """:func:`convert_file` (or with ``dry_run`` its plan, nothing written) described as one
    record of :mod:`envconv.engine.records`: the maps written with their files' facts and
    sizes in bytes, and the seconds spent reading, resampling and writing. Errors raise, as
    :func:`convert_file`'s do."""
    import time

    from .records import plan_record, run_record

    pipeline = convert_pipeline(input_path, output_path, read, resample, write, color, preview)
    start = time.perf_counter()
    if dry_run:
        return plan_record(
            os.fspath(input_path), pipeline.plan(), seconds=time.perf_counter() - start
        )
    written: list[str] = []
    timings: dict[str, float] = {}
    outputs = pipeline.run(keep=False, written=written, warnings=warnings, timings=timings)
    return run_record(os.fspath(input_path), written, outputs, time.perf_counter() - start,
                      timings)  # fmt: skip


def convert_pipeline(input_path, output_path, read=None, resample=None, write=None, color=None,
                     preview=None):  # fmt: skip
    """The :class:`~envconv.engine.pipeline.Pipeline` ``Read → Resample → Write`` of one conversion
    (arguments as :func:`convert_file`'s)."""
    from .pipeline import Pipeline, Read, Resample, Write

    read, resample, write = dict(read or {}), dict(resample or {}), dict(write or {})
    route_face_sets(input_path, read, resample, write)
    return Pipeline([Read(input_path, **read, **(color or {})), Resample(**resample),
                     Write(output_path, preview=preview, **write)])  # fmt: skip


def plan_convert(
    input_path: str | os.PathLike,
    output_path: str | os.PathLike,
    read: dict[str, Any] | None = None,
    resample: dict[str, Any] | None = None,
    write: dict[str, Any] | None = None,
    color: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """What :func:`convert_file` would write, from the input's header alone (no pixels read).

    The engine plans the run as it would run it, and the writer says what it will store
    (:func:`envconv.io.write_plan.plan_write`): nothing here restates their rules. Refuses,
    like a run, what breaks the output policy and what the writer cannot hold.

    Returns a dict: ``files``, ``layout``, ``size`` (N), ``guard``, ``width`` × ``height`` (one
    file), ``levels`` (MIP levels each file holds), ``channels``, ``bit_depth``,
    ``compression`` (None: format default), ``format``, ``input_colorspace``,
    ``working_colorspace`` and ``output_colorspace`` (OCIO names).
    """
    from ..color.ocio import WORKING_COLORSPACE, input_colorspace_of
    from ..io.face_files import first_file

    read, write, color = dict(read or {}), dict(write or {}), dict(color or {})
    resample = dict(resample or {})
    output = convert_pipeline(input_path, output_path, read, resample, write, color).plan()[0]
    stored = output.writes[0]
    route_face_sets(input_path, read, resample, write)
    first = first_file(input_path, read.get("layout"), read.get("faces"))
    level, part = int(read.get("level", 0) or 0), read.get("part")
    metadata = io.read_header(first, level, part)[3]
    config = write.get("ocio_config") or read.get("ocio_config")
    source = input_colorspace_of(metadata, io.read_pixel_type(first, part),
                                 read.get("input_colorspace"), config)  # fmt: skip
    working = input_colorspace_of({}, "float", WORKING_COLORSPACE, config)
    return {
        "files": list(output.files), "layout": output.layout, "size": output.size,
        "guard": output.guard, "width": output.width, "height": output.height,
        "levels": stored.levels, "channels": list(stored.channels),
        "bit_depth": stored.pixel_type, "compression": stored.compression,
        "format": stored.format, "input_colorspace": source, "working_colorspace": working,
        "output_colorspace": stored.colorspace,
    }  # fmt: skip


def route_face_sets(input_path, read: dict, resample: dict, write: dict) -> None:
    """Move a convention that names a skybox face set from resampling to reading or writing.

    ``in_convention`` goes to ``read["faces"]`` when the input is a ``{face}`` path of cube
    faces, and ``out_convention`` to ``write["faces"]`` when the output layout is cube-faces:
    a face set names files and turns faces (:mod:`envconv.layouts.facesets`), which only reading and
    writing can do. Other conventions (``unreal`` on a lat-long, …) stay with resampling.
    The dicts are changed in place.
    """
    from ..layouts import get_layout
    from ..layouts.facesets import is_face_set

    cin, cout = resample.get("in_convention"), resample.get("out_convention")
    if (is_face_set(cin) and "{face}" in os.fspath(input_path) and not read.get("faces")
            and read.get("layout") in (None, "cube-faces")):  # fmt: skip
        read["faces"] = resample.pop("in_convention")
    if (is_face_set(cout) and resample.get("to") is not None and not write.get("faces")
            and get_layout(resample["to"]).name == "cube-faces"):  # fmt: skip
        write["faces"] = resample.pop("out_convention")
