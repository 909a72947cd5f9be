"""Pipelines: a list of steps that reads one source and writes any number of outputs.

A pipeline is what ``envconv read … resample … write …`` runs at the shell, what a graph file
describes (:mod:`envconv.graph`) and what ``envconv batch`` runs once per input. The steps are
plain objects a Python user builds without click:

>>> from envconv.pipeline import Pipeline, Read, Resample, Write
>>> Pipeline([
...     Read("sky.exr"),
...     Resample("cube-vcross", size=512), Write("cross.exr"),
...     Resample("paraboloid", size=256, alpha=True, guard=2), Write("para.exr"),
... ]).run()                                                   # doctest: +SKIP

The fan-out rule
----------------
* ``Read`` sets the *source*. ``Rotate``, ``Exposure`` and ``Colorspace`` that follow it (or
  follow a ``Write``) change the source; every later ``Resample`` sees the change.
* Every ``Resample`` starts from the source as it stands, never from another output, so each
  output is resampled exactly once. Rotations are not applied to pixels at all: they are
  composed and handed to the one resample, so rotating costs no extra filtering.
* ``Exposure`` and ``Colorspace`` placed between a ``Resample`` and its first ``Write`` change
  that output only (e.g. an sRGB preview next to a linear master). ``Rotate`` there is an error:
  it would resample the output a second time.
* ``Write`` writes the latest output, or the source itself when no ``Resample`` has run since the
  ``Read`` (a format change; a pending rotation then resamples into the source's own layout).

Paths in ``Write`` take variables: ``{stem}``, ``{name}``, ``{ext}`` (no dot) and ``{dir}`` of
the input last read, ``{layout}`` and ``{size}`` (N) of what is written, and any user variables.
``{face}`` and ``{level}`` are left for :func:`envconv.io.write`.
"""

from __future__ import annotations

import logging
import math
import os
import re
from dataclasses import dataclass, field
from typing import Any

from . import io
from .envmap import EnvMap
from .errors import EnvconvError, UsageError
from .layouts import get_layout
from .rotation import parse_rotation, rotation_matrix

__all__ = [
    "Step", "Read", "Rotate", "Exposure", "Colorspace", "Resample", "Write",
    "Pipeline", "Output", "expand_path", "path_variables", "compose_rotations", "count_levels",
    "VARIABLES",
]  # fmt: skip

log = logging.getLogger(__name__)

#: Variables every ``Write`` path may use; ``{face}`` and ``{level}`` are io's own.
VARIABLES = ("stem", "name", "ext", "dir", "layout", "size")
_IO_PLACEHOLDERS = ("face", "level")
_VARIABLE = re.compile(r"\{([^{}]*)\}")


class Step:
    """Base class: a named step holding its keyword parameters in ``params``."""

    kind = "step"

    def __init__(self, **params: Any) -> None:
        self.params = params

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.params.items())
        return f"{type(self).__name__}({args})"

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and self.params == other.params  # type: ignore[attr-defined]

    __hash__ = None  # type: ignore[assignment]


class Read(Step):
    """Read a source: ``path`` (None in a batch recipe: the job's input) and io.read options."""

    kind = "read"

    def __init__(self, path: str | os.PathLike | None = None, **options: Any) -> None:
        super().__init__(path=None if path is None else os.fspath(path), **options)

    @property
    def options(self) -> dict[str, Any]:
        return {k: v for k, v in self.params.items() if k != "path"}


class Rotate(Step):
    """Turn the environment by YAW, PITCH, ROLL degrees (see :mod:`envconv.rotation`).

    ``Rotate("90,0,0")``, ``Rotate((90, 0, 0))`` or ``Rotate(yaw=90)``.
    """

    kind = "rotate"

    def __init__(self, angles=None, yaw: float = 0.0, pitch: float = 0.0, roll: float = 0.0):
        if angles is None:
            angles = (yaw, pitch, roll)
        super().__init__(angles=parse_rotation(angles))


class Exposure(Step):
    """Scale colour (not alpha) by 2**stops."""

    kind = "exposure"

    def __init__(self, stops: float) -> None:
        try:
            value = float(stops)
        except (TypeError, ValueError):
            raise UsageError(f"exposure expects a number of stops, got {stops!r}") from None
        if not math.isfinite(value):
            raise UsageError(f"exposure must be finite, got {stops!r}")
        super().__init__(stops=value)


class Colorspace(Step):
    """Convert colour from ``src`` (default: the file's ``oiio:ColorSpace``) to ``dst`` (OCIO)."""

    kind = "colorspace"

    def __init__(self, dst: str, src: str | None = None, config: str | None = None) -> None:
        super().__init__(dst=dst, src=src, config=config)


class Resample(Step):
    """Resample the source into layout ``to``; keywords are :func:`envconv.convert`'s.

    ``mips`` is passed on only when set, to a build whose ``convert`` knows it.
    """

    kind = "resample"

    def __init__(self, to: str, size: int | None = None, samples: int | str = "auto",
                 filter: str = "bilinear", alpha: bool = False, guard: int | str = 0,
                 mips: Any = None, rotate: Any = None, **options: Any) -> None:  # fmt: skip
        super().__init__(to=get_layout(to).name, size=size, samples=samples, filter=filter,
                         alpha=alpha, guard=guard, mips=mips, rotate=rotate, **options)  # fmt: skip

    def convert_kwargs(self, rotation=None) -> dict[str, Any]:
        """Keyword arguments for :func:`envconv.convert`, with ``rotation`` composed first."""
        kwargs = {k: v for k, v in self.params.items() if k not in ("mips", "rotate")}
        rotate = compose_rotations(rotation, self.params["rotate"])
        if rotate is not None:
            kwargs["rotate"] = rotate
        if self.params["mips"] is not None and self.params["mips"] is not False:
            kwargs["mips"] = self.params["mips"]
        return kwargs


class Write(Step):
    """Write the latest output (or the source) to ``path``; other options go to io.write.

    ``makedirs`` creates missing output directories; ``base``, when set, is the directory a
    relative path is taken from once its variables are expanded (a graph file's directory, or
    the batch's working directory), so a path like ``{out}/{stem}.exr`` resolves there too.
    ``preview``, when set, is a path (same variables) for a tone-mapped 8-bit picture of what
    is written (:func:`envconv.preview.preview_picture`).
    """

    kind = "write"
    _OWN = ("path", "makedirs", "base", "preview")

    def __init__(self, path: str | os.PathLike, makedirs: bool = True, base: str | None = None,
                 preview: str | os.PathLike | None = None, **options: Any) -> None:  # fmt: skip
        preview = None if preview is None else os.fspath(preview)
        super().__init__(path=os.fspath(path), makedirs=makedirs, base=base, preview=preview,
                         **options)  # fmt: skip

    @property
    def options(self) -> dict[str, Any]:
        return {k: v for k, v in self.params.items() if k not in self._OWN}

    def target(self, variables: dict[str, Any], key: str = "path") -> str:
        """The output path (or ``key="preview"``: the preview's) with ``variables`` expanded
        (``{face}``/``{level}`` kept)."""
        path = expand_path(self.params[key], variables)
        base = self.params["base"]
        return path if base is None or os.path.isabs(path) else os.path.join(base, path)


@dataclass
class Output:
    """One output of a pipeline: what was (or would be) written.

    ``width``/``height`` are one file's size in pixels at level 0; ``levels`` counts MIP levels;
    ``files`` lists every file (empty when the output was not written); ``envmap`` holds the
    pixels when the pipeline ran with ``keep=True``.
    """

    input: str | None
    layout: str
    size: int
    guard: int
    width: int
    height: int
    levels: int = 1
    files: list[str] = field(default_factory=list)
    envmap: EnvMap | None = None


def path_variables(input_path: str | os.PathLike | None) -> dict[str, str]:
    """``stem``, ``name``, ``ext`` (without the dot) and ``dir`` of an input path."""
    if input_path is None:
        return {}
    path = os.fspath(input_path)
    name = os.path.basename(path)
    stem, ext = os.path.splitext(name)
    return {"stem": stem, "name": name, "ext": ext.lstrip("."), "dir": os.path.dirname(path) or "."}


def template_names(template: str) -> list[str]:
    """Names of the ``{variables}`` in a path template."""
    return _VARIABLE.findall(template)


def expand_path(template: str, variables: dict[str, Any]) -> str:
    """Replace ``{name}`` in ``template``; ``{face}``/``{level}`` stay; unknown names raise."""

    def substitute(match: re.Match) -> str:
        name = match.group(1)
        if name in _IO_PLACEHOLDERS:
            return match.group(0)
        if name not in variables:
            known = ", ".join(f"{{{k}}}" for k in (*variables, *_IO_PLACEHOLDERS))
            raise UsageError(f"unknown variable {{{name}}} in path {template!r}; known: {known}")
        return str(variables[name])

    return _VARIABLE.sub(substitute, template)


def compose_rotations(first, second):
    """YAW,PITCH,ROLL of turning by ``first`` then by ``second`` (either may be None)."""
    if first is None or second is None:
        return second if first is None else first
    matrix = rotation_matrix(*parse_rotation(second)) @ rotation_matrix(*parse_rotation(first))
    pitch = math.asin(max(-1.0, min(1.0, matrix[2, 1])))
    if abs(math.cos(pitch)) > 1e-9:
        yaw = math.atan2(-matrix[2, 0], matrix[2, 2])
        roll = math.atan2(-matrix[0, 1], matrix[1, 1])
    else:  # gimbal lock: put the whole turn about Y into yaw
        yaw, roll = math.atan2(matrix[0, 2], matrix[0, 0]), 0.0
    return tuple(math.degrees(a) for a in (yaw, pitch, roll))


def count_levels(width: int, height: int, mips: Any) -> int:
    """MIP levels of a ``width`` × ``height`` file, as :mod:`envconv.mips` counts them.

    None or False: 1. True, 0 or "all": the full round-down chain to 1×1, floor(log2 max) + 1.
    K: at most K levels.
    """
    if mips is None or mips is False:
        return 1
    full = max(int(width), int(height), 1).bit_length()
    if mips is True or isinstance(mips, str) or int(mips) == 0:
        return full
    return max(1, min(int(mips), full))


class Pipeline:
    """An ordered list of steps, run with the fan-out rule of this module.

    Parameters
    ----------
    steps : sequence of Step
        The steps. A recipe for many inputs starts without a ``Read`` (or with ``Read()``), and
        gets its input from ``run(input=...)``.
    variables : dict, optional
        User variables for ``Write`` paths, e.g. ``{"out": "build"}`` for ``{out}/{stem}.exr``.
    """

    def __init__(self, steps, variables: dict[str, Any] | None = None) -> None:
        self.steps = tuple(steps)
        self.variables = dict(variables or {})
        for index, step in enumerate(self.steps, 1):
            if not isinstance(step, Step):
                raise UsageError(f"step {index}: expected a pipeline step, got {step!r}")

    def __repr__(self) -> str:
        return f"Pipeline({list(self.steps)!r})"

    def bound(self, input: str | os.PathLike | None = None) -> list[Step]:
        """The steps with ``input`` as the source of a recipe (a leading or path-less Read)."""
        steps = list(self.steps)
        if input is not None:
            if not steps or not isinstance(steps[0], Read):
                steps.insert(0, Read())
            steps = [Read(input, **s.options) if isinstance(s, Read) and s.params["path"] is None
                     else s for s in steps]  # fmt: skip
        return steps

    def validate(self, input=None, require_writes: bool = False) -> None:
        """Check the order of the steps and the ``Write`` paths, without touching any file.

        Raises UsageError naming the step (1-based) and the problem.
        """
        steps = self.bound(input) if input is not None else list(self.steps)
        known = set(VARIABLES) | set(self.variables) | set(_IO_PLACEHOLDERS)
        have_source = pending = False
        layout = None
        for index, step in enumerate(steps, 1):
            where = f"step {index} ({step.kind})"
            if isinstance(step, Read):
                if step.params["path"] is None and input is None:
                    raise UsageError(f"{where}: read needs a file (only a batch supplies one)")
                have_source, pending = True, False
                continue
            if not have_source:
                raise UsageError(f"{where}: comes before any read")
            if isinstance(step, Rotate) and pending:
                raise UsageError(f"{where}: rotate follows a resample, so the output would be "
                                 "resampled twice; put rotate before resample")  # fmt: skip
            if isinstance(step, Resample):
                pending, layout = True, step.params["to"]
            elif isinstance(step, Write):
                if pending:
                    try:
                        io.output_paths(layout, step.params["path"])
                    except EnvconvError as exc:
                        raise UsageError(f"{where}: path: {exc}") from None
                pending = False
                for name in template_names(step.params["path"]):
                    if name not in known:
                        raise UsageError(
                            f"{where}: path: unknown variable {{{name}}} in "
                            f"{step.params['path']!r}; known: "
                            + ", ".join(f"{{{k}}}" for k in sorted(known))
                        )
            if require_writes and pending and not _written_later(steps, index):
                raise UsageError(f"{where}: this resample is never written; add a write step")

    def run(self, input=None, keep: bool = True, written: list[str] | None = None) -> list[Output]:
        """Run the pipeline; return one :class:`Output` per resample (or plain write).

        ``written``, when given, collects each file as soon as it is written, so a caller still
        knows what was written if a later step fails.
        """
        from ._walk import Walk

        self.validate(input)
        return Walk(self, executing=True, keep=keep, written=written).walk(self.bound(input))

    def plan(self, input=None) -> list[Output]:
        """What ``run`` would write (layouts, sizes, levels, files), reading headers only."""
        from ._walk import Walk

        self.validate(input)
        outputs = Walk(self, executing=False).walk(self.bound(input))
        return [o for o in outputs if o.files]

    def output_files(self, input=None) -> list[str]:
        """Every file ``run`` would write (reads headers only when a path needs ``{size}``)."""
        return [f for output in self.plan(input) for f in output.files]


def _written_later(steps: list[Step], index: int) -> bool:
    for step in steps[index:]:
        if isinstance(step, Write):
            return True
        if isinstance(step, (Resample, Read)):
            return False
    return False
