"""File-level operations that the CLI, the pipeline and batch jobs share."""

from __future__ import annotations

import os
from typing import Any

from . import io
from .resample import convert

__all__ = ["convert_file"]


def convert_file(
    input_path: str | os.PathLike,
    output_path: str | os.PathLike,
    read: dict[str, Any] | None = None,
    resample: dict[str, Any] | None = None,
    write: dict[str, Any] | None = None,
) -> list[str]:
    """Read ``input_path``, resample, write ``output_path``; return the paths written.

    ``read``, ``resample`` and ``write`` are keyword arguments for :func:`envconv.io.read`,
    :func:`envconv.resample.convert` and :func:`envconv.io.write`. The output path is checked
    against the layout before any pixel is read, so a bad ``{face}`` path fails fast.
    """
    resample = dict(resample or {})
    to = resample.pop("to")
    io.output_paths(to, output_path)
    source = io.read(input_path, **(read or {}))
    result = convert(source, to, **resample)
    return io.write(result, output_path, **(write or {}))
