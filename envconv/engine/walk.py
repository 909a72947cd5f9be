"""The one walker over pipeline steps: it checks, plans and runs them.

Private to :mod:`envconv.engine.pipeline`, whose docstring states the rules implemented here. One
:class:`Walk` goes over the steps in one of three modes, with the same state changes in each, so
what is checked, what is planned and what runs cannot drift apart:

* ``check``: no file is touched; the order of the steps and the ``Write`` paths are checked.
* ``plan``: headers only; every output's layout, size, levels and files, and each write's
  output settings (bit depth, compression, colour space).
* ``run``: pixels are read, prepared, resampled, changed and written.
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, replace
from types import SimpleNamespace
from typing import Any

from .. import io
from ..errors import EnvconvError, ImageIOError, UsageError
from ..io.face_files import literal_path
from ..layouts import get_layout
from ..layouts.base import VIEW_OPTIONS
from .checks import check_colorspace_name, check_conventions, check_levels, working_space
from .steps import (
    _IO_PLACEHOLDERS,
    VARIABLES,
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
    template_names,
)  # fmt: skip

__all__ = ["Walk", "SourceHeader"]

log = logging.getLogger(__name__)
MODES = ("check", "plan", "run")


class SourceHeader:
    """What a plan knows of a source: layout, size, guard, channels and pixel type, from the
    header."""

    def __init__(self, path: str, options: dict[str, Any]) -> None:
        from ..layouts.detect import place_image

        level = int(options.get("level", 0) or 0)
        layout, first = options.get("layout"), path
        if "{face}" in path:
            from ..io.face_files import find_face_files

            files = find_face_files(path, layout, options.get("faces"))
            layout, first = files.layout, files.paths[0]
        width, height, channels, metadata = io.read_header(first, level, options.get("part"))
        if layout is not None and get_layout(layout).multi_file:
            width *= get_layout(layout).n_faces
        found, guard, size = place_image(width, height, metadata, layout, level=level)
        self.layout, self.guard, self.channels, self.size = found, guard, channels, size
        self.pixel_type = io.read_pixel_type(first, options.get("part"))


@dataclass
class _Latest:
    """The latest output: its record, its pixels (run mode), whether a write has taken it,
    whether it is the source itself, whether a rotate came after it, the colour space a
    colorspace step put it in ((name, config) or None), and the resample's keywords (check
    mode: what the writes can be checked against before any header is read)."""

    record: Output | None
    env: Any
    layout: str | None
    written: bool = False
    is_source: bool = False
    stale_at: int | None = None
    space: tuple[str, str | None] | None = None
    request: dict[str, Any] | None = None


class Walk:
    """One pass over the steps in ``mode`` (``check``, ``plan`` or ``run``).

    ``written`` collects each file as it is written (run mode); ``warnings`` collects one-line
    warnings (NaN/Inf, clipping) when it is a list, else they are logged; ``timings`` adds up
    the seconds spent reading (and preparing), resampling and writing (run mode). ``targets``
    lists (file, no_clobber) of every write (plan and run modes).
    """

    def __init__(self, variables: dict[str, str], mode: str, keep: bool = False,
                 written: list[str] | None = None, warnings: list[str] | None = None,
                 timings: dict[str, float] | None = None) -> None:  # fmt: skip
        assert mode in MODES, mode
        self.variables, self.mode, self.keep = variables, mode, keep
        self.timings = timings if timings is not None else {}
        self.written = written if written is not None else []
        self.warnings = warnings
        self.outputs: list[Output] = []
        self.targets: list[tuple[str, bool]] = []
        self.source: Any = None
        self.source_space: tuple[str, str | None] | None = None
        self.input: str | None = None
        self.rotation = None
        self.latest: _Latest | None = None
        self.index = 0

    def walk(self, steps: list[Step], require_writes: bool = False) -> list[Output]:
        for self.index, step in enumerate(steps, 1):
            if not isinstance(step, Read) and self.input is None and self.source is None:
                raise UsageError(f"{self._where(step)}: comes before any read")
            getattr(self, f"_{step.kind}")(step)
            if (
                require_writes
                and isinstance(step, Resample)
                and not _written_later(steps, self.index)
            ):
                raise UsageError(f"{self._where(step)}: this resample is never written; "
                                 "add a write step")  # fmt: skip
        return self.outputs

    def _where(self, step: Step) -> str:
        return f"step {self.index} ({step.kind})"

    def _warn(self, messages: list[str]) -> None:
        if self.warnings is None:
            for message in messages:
                log.warning("%s", message)
        else:
            self.warnings.extend(messages)

    # --- read, rotate, pixel steps ----------------------------------------------------------

    def _read(self, step: Read) -> None:
        self.input = step.params["path"]
        if self.input is None:
            raise UsageError(f"{self._where(step)}: read needs a file (only a batch supplies one)")
        if self.mode == "run":
            from ..color.prepare import prepare_input

            start = time.perf_counter()
            source = io.read(self.input, **step.read_options)
            self.source, notes = prepare_input(source, **step.prepare_options)
            self._add_time("read", start)
            self._warn(notes)
        elif self.mode == "plan":
            self.source = SourceHeader(self.input, step.read_options)
        else:
            layout = step.read_options.get("layout")
            self.source = SimpleNamespace(layout=None if layout is None else get_layout(layout))
            options = step.read_options
            check_colorspace_name(options.get("input_colorspace"), options.get("ocio_config"))
        self.rotation, self.latest, self.source_space = None, None, None

    def _add_time(self, phase: str, start: float, record: Output | None = None) -> float:
        """Add the seconds since ``start`` to ``phase`` (and to ``record``'s own)."""
        seconds = time.perf_counter() - start
        self.timings[phase] = self.timings.get(phase, 0.0) + seconds
        if record is not None:
            record.seconds[phase] = record.seconds.get(phase, 0.0) + seconds
        return seconds

    def _rotate(self, step: Rotate) -> None:
        latest = self.latest
        if latest is not None and not latest.written:
            raise UsageError(f"{self._where(step)}: rotate follows a resample, so the output "
                             "would be resampled twice; put rotate before resample")  # fmt: skip
        if latest is not None and latest.is_source:
            self.latest = None  # a later write resamples the turned source into its layout
        elif latest is not None:
            latest.stale_at = self.index
        self.rotation = compose_rotations(self.rotation, step.params["angles"])

    def _exposure(self, step: Exposure) -> None:
        self._pixel_step(lambda env: _apply_exposure(env, step.params["stops"]), None)

    def _colorspace(self, step: Colorspace) -> None:
        params = step.params
        if self.mode == "check":
            for name in (params["dst"], params["src"]):
                check_colorspace_name(name, params["config"])
        self._pixel_step(lambda env: _apply_colorspace(env, **params),
                         (params["dst"], params["config"]))  # fmt: skip

    def _pixel_step(self, fn, space) -> None:
        """Change the latest output alone while it is unwritten; after a write (or with no
        output), change the source and the latest output both."""
        latest, run = self.latest, self.mode == "run"
        if latest is not None and not latest.written:
            self._change_latest(fn, space, run)
            return
        if run:
            self.source = fn(self.source)
        self.source_space = space or self.source_space
        if latest is not None:
            if latest.is_source:
                latest.env = self.source if run else None
                latest.space = self.source_space
                if latest.record is not None and latest.record.envmap is not None:
                    latest.record.envmap = self.source
            else:
                self._change_latest(fn, space, run)

    def _change_latest(self, fn, space, run: bool) -> None:
        latest = self.latest
        if run:
            latest.env = fn(latest.env)
            if latest.record.envmap is not None:
                latest.record.envmap = latest.env
        latest.space = space or latest.space

    # --- resample and write -----------------------------------------------------------------

    def _resample(self, step: Resample) -> None:
        self._make_output(
            step.params["to"], step.convert_kwargs(self.rotation), step.params["mips"]
        )

    def _make_output(self, to, kwargs: dict[str, Any], mips: Any) -> None:
        from ..resample.options import check_output, output_layout

        view = {k: kwargs.get(k) for k in VIEW_OPTIONS}
        layout = check_output(to, kwargs.get("size"), **view)
        record, env = None, None
        if self.mode != "run" and "to" in kwargs:
            check_conventions({**kwargs, "mips": mips}, getattr(self.source, "layout", None))
        if self.mode != "check":
            guard = kwargs.get("guard", 0)
            guard = 0 if guard == "fill" else int(guard)
            if self.mode == "run":
                from ..resample.convert import convert

                start = time.perf_counter()
                env = convert(self.source, **kwargs)
                layout, size, channels = env.layout, env.size, env.channels
            else:
                from ..resample.options import output_channels

                source = SimpleNamespace(size=self.source.size, layout=self.source.layout)
                layout, size = output_layout(source, to, kwargs.get("size"), **view,
                                             out_convention=kwargs.get("out_convention"),
                                             mips=mips, guard=kwargs.get("guard", 0))  # fmt: skip
                channels = output_channels(self.source.channels, kwargs.get("alpha", False))
            width, height = layout.file_size(size, guard)
            record = Output(self.input, layout.name, int(size), guard, width, height,
                            count_levels(width, height, mips), channels=tuple(channels))  # fmt: skip
            if self.mode == "run":
                self._add_time("resample", start, record)
            record.envmap = env if self.keep else None
            self.outputs.append(record)
        self.latest = _Latest(record, env, layout.name, space=self.source_space,
                              request={**kwargs, "mips": mips})  # fmt: skip

    def _write(self, step: Write) -> None:
        self._check_template(step)
        latest = self.latest
        if latest is not None and latest.stale_at is not None:
            raise UsageError(f"{self._where(step)}: the latest output was resampled before the "
                             f"rotate of step {latest.stale_at}; add a resample after the "
                             "rotate")  # fmt: skip
        if latest is None:
            if self.rotation is not None:
                layout = None if self.mode == "check" else self.source.layout
                kwargs = {} if self.mode == "check" else {
                    "to": layout, "size": self.source.size, "guard": self.source.guard,
                    "rotate": self.rotation}  # fmt: skip
                self._make_output(layout or "latlong", kwargs, None)
                self.latest.layout = None if layout is None else layout.name
            else:
                self._write_source()
        if self.mode != "check":
            self._write_files(step, self.latest)
        self.latest.written = True

    def _check_template(self, step: Write) -> None:
        known = set(VARIABLES) | set(self.variables) | set(_IO_PLACEHOLDERS)
        template = step.params["path"]
        for name in template_names(template) + template_names(step.params["preview"] or ""):
            if name not in known:
                raise UsageError(f"{self._where(step)}: path: unknown variable {{{name}}} in "
                                 f"{template!r}; known: "
                                 + ", ".join(f"{{{k}}}" for k in sorted(known)))  # fmt: skip
        layout = self.latest.layout if self.latest is not None else None
        if layout is not None and not self.latest.is_source:
            try:
                io.output_paths(layout, template, faces=step.options.get("faces"))
                if self.mode == "check":
                    check_levels(layout, template, self.latest.request or {})
            except EnvconvError as exc:
                raise UsageError(f"{self._where(step)}: path: {exc}") from None
        if self.mode == "check":
            options = step.options
            check_colorspace_name(options.get("output_colorspace"), options.get("ocio_config"))

    def _write_source(self) -> None:
        record, src = None, self.source
        if self.mode != "check":
            width, height = src.layout.file_size(src.size, src.guard)
            record = Output(self.input, src.layout.name, src.size, src.guard, width, height,
                            channels=tuple(src.channels))  # fmt: skip
            if self.keep and self.mode == "run":
                record.envmap = src
            self.outputs.append(record)
        env = src if self.mode == "run" else None
        layout = None if self.mode == "check" else src.layout.name
        self.latest = _Latest(record, env, layout, is_source=True, space=self.source_space)

    def _write_files(self, step: Write, latest: _Latest) -> None:
        record = latest.record
        variables = {**path_variables(self.input), "layout": record.layout, "size": record.size}
        path = step.target(variables, user=self.variables)
        options = dict(step.options)
        if latest.space is not None and not options.get("output_colorspace"):
            # A colorspace step chose the colour space: the write keeps it (and tags it).
            options["output_colorspace"] = latest.space[0]
            if latest.space[1] and not options.get("ocio_config"):
                options["ocio_config"] = latest.space[1]
        plan = io.plan_write(record.layout, path, record.size, record.guard, record.levels,
                             record.channels, self.source.pixel_type, working_space(),
                             **options)  # fmt: skip
        record.writes.append(plan)
        preview = None
        if step.params["preview"]:  # one file: its braces are literal (io.face_files)
            preview = literal_path(step.target(variables, "preview", self.variables))
        files = [*plan.files, *([preview] if preview else [])]
        self.targets += [(f, step.params["no_clobber"]) for f in files]
        if self.mode == "run":
            start = time.perf_counter()
            if step.params["makedirs"]:
                _make_folders(path, files)
            files = self._write_env(latest.env, path, preview, options)
            self._add_time("write", start, record)
        self.written.extend(files)
        record.files.extend(files)

    def _write_env(self, env, path: str, preview: str | None, options) -> list[str]:
        notes: list[str] = []
        files = io.write(env, path, warnings=notes, **options)
        self._warn(notes)
        if preview is not None:
            files.append(_write_preview(env, preview))
        log.info("wrote %s", ", ".join(files))
        return files


def _make_folders(path: str, files: list[str]) -> None:
    """Make the missing folders of ``files``, the final names of a write to ``path`` (a
    ``{face}`` in a folder name makes one folder per face)."""
    for directory in dict.fromkeys(os.path.dirname(os.path.abspath(f)) for f in files):
        try:
            os.makedirs(directory, exist_ok=True)
        except OSError as exc:  # a regular file on the way, /proc, no permission
            raise ImageIOError(f"cannot write {path}: cannot make folder {directory}: "
                               f"{exc.strerror or exc}") from None  # fmt: skip


def _written_later(steps: list[Step], index: int) -> bool:
    for step in steps[index:]:
        if isinstance(step, Write):
            return True
        if isinstance(step, (Resample, Read)):
            return False
    return False


def _write_preview(env, path: str) -> str:
    """A tone-mapped 8-bit picture of ``env`` at ``path`` (a write step's ``preview``)."""
    from ..io.picture import write_picture
    from ..views.preview import preview_picture

    return write_picture(preview_picture(env), path)


def _apply_exposure(env, stops: float):
    from ..color.ocio import apply_exposure
    from ..envmap import map_levels

    return map_levels(env, lambda pixels: apply_exposure(pixels, stops))


def _apply_colorspace(env, dst: str, src: str | None, config: str | None):
    """``env`` converted by OCIO from ``src`` (default: its ``oiio:ColorSpace``) to ``dst``."""
    from ..color.ocio import (
        colorspace_from_metadata,
        config_for,
        convert_keeping_nonfinite,
        metadata_name,
        resolve_colorspace,
    )
    from ..envmap import map_levels

    ocio = config_for(config)
    if src is None:
        src = colorspace_from_metadata(env.metadata.get("oiio:ColorSpace"), ocio)
    if not src:
        raise UsageError("colorspace: the input's colour space is unknown; give it (--from)")
    src, dst = resolve_colorspace(ocio, src), resolve_colorspace(ocio, dst)
    metadata = {**env.metadata, "oiio:ColorSpace": metadata_name(ocio, dst)}
    metadata.pop("chromaticities", None)
    changed = map_levels(env, lambda px: convert_keeping_nonfinite(px, src, dst, ocio))
    return replace(changed, metadata=metadata)
