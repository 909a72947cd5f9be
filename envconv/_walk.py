"""Running and planning pipelines: the walk over the steps behind :class:`Pipeline`.

Private to :mod:`envconv.pipeline`, whose docstring states the fan-out rule implemented here.
"""

from __future__ import annotations

import dataclasses
import inspect
import logging
import os
from types import SimpleNamespace
from typing import Any

import numpy as np

from . import io
from .envmap import EnvMap
from .errors import UsageError
from .layouts import get_layout
from .pipeline import (
    Colorspace,
    Exposure,
    Output,
    Read,
    Resample,
    Rotate,
    Step,
    Write,
    compose_rotations,
    count_levels,
    path_variables,
)  # fmt: skip
from .resample import convert, default_size

__all__ = ["Walk", "SourceHeader"]

log = logging.getLogger(__name__)


class SourceHeader:
    """What a plan knows of a source: layout, size, guard and channels, from the header."""

    def __init__(self, path: str, options: dict[str, Any]) -> None:
        from .detect import place_image

        level = int(options.get("level", 0) or 0)
        layout, first = options.get("layout"), path
        if "{face}" in path:
            from .io.face_files import find_face_files

            files = find_face_files(path, layout, options.get("faces"))
            layout, first = files.layout, files.paths[0]
        width, height, channels, metadata = io.read_header(first, level, options.get("part"))
        if layout is not None and get_layout(layout).multi_file:
            width *= get_layout(layout).n_faces
        found, guard, size = place_image(width, height, metadata, layout, level=level)
        self.layout, self.guard, self.channels, self.size = found, guard, channels, size


class Walk:
    """One pass over the steps; executes them, or only plans them from headers."""

    def __init__(self, pipeline, executing: bool, keep: bool = False, written=None):
        self.pipeline, self.executing, self.keep = pipeline, executing, keep
        self.written = written if written is not None else []
        self.outputs: list[Output] = []
        self.source: Any = None
        self.input: str | None = None
        self.rotation = None
        self.current: tuple[Output, Any] | None = None  # (record, EnvMap or None) unwritten-first
        self.current_written = False

    def walk(self, steps: list[Step]) -> list[Output]:
        for step in steps:
            getattr(self, f"_{step.kind}")(step)
        return self.outputs

    def _read(self, step: Read) -> None:
        self.input = step.params["path"]
        if self.executing:
            self.source = io.read(self.input, **step.options)
        else:
            self.source = SourceHeader(self.input, step.options)
        self.rotation, self.current = None, None

    def _source_or_output(self):
        if self.current is not None and not self.current_written:
            return "output"
        self.current = None
        return "source"

    def _rotate(self, step: Rotate) -> None:
        self._source_or_output()
        self.rotation = compose_rotations(self.rotation, step.params["angles"])

    def _exposure(self, step: Exposure) -> None:
        self._pixel_op(lambda env: _apply_exposure(env, step.params["stops"]))

    def _colorspace(self, step: Colorspace) -> None:
        self._pixel_op(lambda env: _apply_colorspace(env, **step.params))

    def _pixel_op(self, fn) -> None:
        if not self.executing:
            return
        if self._source_or_output() == "output":
            record, env = self.current
            env = fn(env)
            self.current = (record, env)
            if record.envmap is not None:
                record.envmap = env
        else:
            self.source = fn(self.source)

    def _resample(self, step: Resample) -> None:
        kwargs = step.convert_kwargs(self.rotation)
        self._make_output(step.params["to"], kwargs, step.params["mips"])

    def _make_output(self, to: str, kwargs: dict[str, Any], mips: Any) -> None:
        layout = get_layout(to)
        guard = kwargs.get("guard", 0)
        guard = 0 if guard == "fill" else int(guard)
        if self.executing:
            env = convert(self.source, **kwargs)
            size = env.size
        else:
            env = None
            size = kwargs.get("size") or default_size(
                SimpleNamespace(size=self.source.size, layout=self.source.layout), layout,
                kwargs.get("out_convention"),
            )  # fmt: skip
        width, height = layout.file_size(size, guard)
        levels = count_levels(width, height, mips)
        record = Output(self.input, layout.name, int(size), guard, width, height, levels)
        record.envmap = env if self.keep else None
        self.outputs.append(record)
        self.current, self.current_written = (record, env), False

    def _write(self, step: Write) -> None:
        if self.current is None:
            if self.rotation is not None:
                src = self.source
                self._make_output(src.layout.name, {"to": src.layout.name, "size": src.size,
                                  "guard": src.guard, "rotate": self.rotation}, None)  # fmt: skip
            else:
                self._write_source()
        record, env = self.current
        variables = {**path_variables(self.input), **self.pipeline.variables,
                     "layout": record.layout, "size": record.size}  # fmt: skip
        path = step.target(variables)
        files = _output_paths(record.layout, path, record.levels, step.options.get("faces"))
        preview = step.target(variables, "preview") if step.params.get("preview") else None
        if self.executing:
            if step.params["makedirs"]:
                for directory in {os.path.dirname(os.path.abspath(f)) for f in files}:
                    os.makedirs(directory, exist_ok=True)
            files = io.write(env, path, **step.options)
            if preview is not None:
                files.append(_write_preview(env, preview))
            log.info("wrote %s", ", ".join(files))
        elif preview is not None:
            files = [*files, preview]
        self.written.extend(files)
        record.files.extend(files)
        self.current_written = True

    def _write_source(self) -> None:
        src = self.source
        width, height = src.layout.file_size(src.size, src.guard)
        record = Output(self.input, src.layout.name, src.size, src.guard, width, height,
                        envmap=src if (self.keep and self.executing) else None)  # fmt: skip
        self.outputs.append(record)
        self.current, self.current_written = (record, src if self.executing else None), False


def _write_preview(env, path: str) -> str:
    """A tone-mapped 8-bit picture of ``env`` at ``path`` (a write step's ``preview``)."""
    from .io.picture import write_picture
    from .preview import preview_picture

    return write_picture(preview_picture(env), path)


def _output_paths(layout: str, path: str, levels: int, faces=None) -> list[str]:
    """io.output_paths, expanding ``{level}`` here if this io does not know it yet."""
    if faces is not None:
        return io.output_paths(layout, path, levels, faces=faces)
    if "levels" in inspect.signature(io.output_paths).parameters:
        return io.output_paths(layout, path, levels)
    files = io.output_paths(layout, path)
    if "{level}" not in path:
        return files
    return [f.replace("{level}", str(k)) for k in range(levels) for f in files]


def _colour_indices(env: EnvMap) -> list[int]:
    return [i for i in range(len(env.channels)) if i != env.alpha_index]


def _map_pixels(env: EnvMap, fn, metadata=None) -> EnvMap:
    """``env`` with ``fn`` applied to its colour channels (alpha untouched) and mip levels."""
    idx = _colour_indices(env)

    def apply(pixels: np.ndarray) -> np.ndarray:
        out = pixels.copy()
        out[..., idx] = fn(pixels[..., idx])
        return out

    changes: dict[str, Any] = {"pixels": apply(env.pixels)}
    if getattr(env, "levels", None) is not None:
        changes["levels"] = [changes["pixels"], *(apply(level) for level in env.levels[1:])]
    if metadata is not None:
        changes["metadata"] = metadata
    return dataclasses.replace(env, **changes)


def _apply_exposure(env: EnvMap, stops: float) -> EnvMap:
    try:
        from .color import apply_exposure
    except ImportError:

        def apply_exposure(pixels, stops):
            return pixels * np.float32(2.0**stops)

    return _map_pixels(env, lambda colour: apply_exposure(colour, stops))


def _apply_colorspace(env: EnvMap, dst: str, src: str | None, config: str | None) -> EnvMap:
    try:
        from .color import convert_colorspace, load_config
    except ImportError:
        raise UsageError("colorspace: this envconv build has no colour management") from None
    ocio = load_config(config)
    if src is None:
        from .color import colorspace_from_metadata

        src = colorspace_from_metadata(env.metadata.get("oiio:ColorSpace"), ocio)
    if not src:
        raise UsageError("colorspace: the input's colour space is unknown; give it (--from)")
    return _map_pixels(
        env,
        lambda colour: convert_colorspace(colour, src, dst, ocio),
        metadata={**env.metadata, "oiio:ColorSpace": dst},
    )
