"""The steps of a pipeline (:mod:`envconv.engine.pipeline`): plain objects a Python user builds
without click, the ``Output`` record of what a pipeline writes, and the rules for ``Write``
paths (variables) and MIP level counts.

``envconv convert``, a shell chain (``envconv read … resample … write …``), a graph file and
every batch item are all made of these steps and run by one walker (:mod:`envconv.engine.walk`).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from typing import Any

from ..envmap import EnvMap
from ..errors import UsageError
from ..layouts import get_layout
from ..layouts.rotation import parse_rotation, rotation_matrix
from ..limits import check_level, check_stops

__all__ = [
    "Step", "Read", "Rotate", "Exposure", "Colorspace", "Resample", "Write", "Output",
    "expand_path", "path_variables", "template_names", "check_variables", "compose_rotations",
    "count_levels", "VARIABLES", "PREPARE_OPTIONS",
]  # fmt: skip

#: Variables every ``Write`` path may use; ``{face}`` and ``{level}`` are io's own.
VARIABLES = ("stem", "name", "ext", "dir", "layout", "size")
_IO_PLACEHOLDERS = ("face", "level")
#: A ``{name}`` in a path template; doubled braces (``{{``, ``}}``) are literal ones.
_VARIABLE = re.compile(r"\{\{|\}\}|\{([^{}]*)\}")
#: ``Read`` options that prepare the source after reading (:func:`envconv.color.prepare.prepare_input`).
PREPARE_OPTIONS = ("exposure", "fix_nonfinite", "clamp_negative")


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
    """Read a source: ``path`` (None in a batch recipe: the job's input) and its options.

    Options are :func:`envconv.io.read`'s (``layout``, ``level``, ``part``,
    ``input_colorspace``, ``ocio_config``) and :func:`envconv.color.prepare.prepare_input`'s
    (``exposure``, ``fix_nonfinite``, ``clamp_negative``: NaN/Inf, range), applied in that order
    right after reading, whatever runs the step (``convert``, a chain, a graph file, a batch).
    """

    kind = "read"

    def __init__(self, path: str | os.PathLike | None = None, **options: Any) -> None:
        if options.get("level") is not None:
            options["level"] = check_level(options["level"])
        if options.get("exposure") is not None:
            options["exposure"] = check_stops(options["exposure"])
        super().__init__(path=None if path is None else os.fspath(path), **options)

    @property
    def options(self) -> dict[str, Any]:
        """Every option (``path`` aside)."""
        return {k: v for k, v in self.params.items() if k != "path"}

    @property
    def read_options(self) -> dict[str, Any]:
        """The options for :func:`envconv.io.read`."""
        return {k: v for k, v in self.options.items() if k not in PREPARE_OPTIONS}

    @property
    def prepare_options(self) -> dict[str, Any]:
        """The options for :func:`envconv.color.prepare.prepare_input`."""
        return {k: v for k, v in self.options.items() if k in PREPARE_OPTIONS}


class Rotate(Step):
    """Turn the environment by YAW, PITCH, ROLL degrees (see :mod:`envconv.layouts.rotation`).

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
        super().__init__(stops=check_stops(stops))


class Colorspace(Step):
    """Convert colour from ``src`` (default: the file's ``oiio:ColorSpace``) to ``dst`` (OCIO)."""

    kind = "colorspace"

    def __init__(self, dst: str, src: str | None = None, config: str | None = None) -> None:
        super().__init__(dst=dst, src=src, config=config)


class Resample(Step):
    """Resample the source into layout ``to``; keywords are :func:`envconv.convert`'s.

    ``mips`` is passed on only when set, to a build whose ``convert`` knows it. The numbers
    and the roughness are checked here, before any file is opened (:mod:`envconv.limits`).
    """

    kind = "resample"

    def __init__(self, to: str, size: int | None = None, samples: int | str = "auto",
                 filter: str | None = None, alpha: bool = False, guard: int | str = 0,
                 mips: Any = None, rotate: Any = None, **options: Any) -> None:  # fmt: skip
        from ..resample.options import check_roughness, check_size

        check_size(size)  # N or a view's WxH, each within envconv.limits' bound
        if options.get("roughness") is not None:
            check_roughness(options["roughness"])
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
    is written (:func:`envconv.views.preview.preview_picture`). ``no_clobber`` refuses, before any
    work, to replace a file that exists (``-n/--no-clobber``).
    """

    kind = "write"
    _OWN = ("path", "makedirs", "base", "preview", "no_clobber")

    def __init__(self, path: str | os.PathLike, makedirs: bool = True, base: str | None = None,
                 preview: str | os.PathLike | None = None, no_clobber: bool = False,
                 **options: Any) -> None:  # fmt: skip
        preview = None if preview is None else os.fspath(preview)
        super().__init__(path=os.fspath(path), makedirs=makedirs, base=base, preview=preview,
                         no_clobber=bool(no_clobber), **options)  # fmt: skip

    @property
    def options(self) -> dict[str, Any]:
        return {k: v for k, v in self.params.items() if k not in self._OWN}

    def target(self, variables: dict[str, Any], key: str = "path",
               user: dict[str, str] | None = None) -> str:  # fmt: skip
        """The output path (or ``key="preview"``: the preview's) with ``variables`` and the
        ``user`` variables expanded (:func:`expand_path`; ``{face}``/``{level}`` kept)."""
        path = expand_path(self.params[key], variables, user)
        base = self.params["base"]
        return path if base is None or os.path.isabs(path) else os.path.join(base, path)


@dataclass
class Output:
    """One output of a pipeline: what was (or would be) written.

    ``width``/``height`` are one file's size in pixels at level 0; ``levels`` counts MIP levels;
    ``channels`` are the output's channels; ``files`` lists every file (empty when the output
    was not written); ``writes`` holds, for each write of this output, what the writer stores
    (:class:`envconv.io.write_plan.WritePlan`: files, format, pixel type, channels, levels;
    from a plan, and from a run's own plan); ``seconds`` the time its resample and writes took
    in a run (``resample``, ``write``); ``envmap`` holds the pixels when the pipeline ran with
    ``keep=True``.
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
    channels: tuple[str, ...] = ()
    writes: list[Any] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)


def path_variables(input_path: str | os.PathLike | None) -> dict[str, str]:
    """``stem``, ``name``, ``ext`` (without the dot) and ``dir`` of an input path.

    Values are file names as they are, their braces escaped (doubled) so that an output path
    never expands a ``{level}`` or ``{face}`` of an input's name as its own. A ``{face}`` input
    (a set of files) names its set: ``sky_{face}.hdr`` gives ``stem`` ``sky`` and ``name``
    ``sky.hdr`` (the ``{face}`` and the ``_``, ``-`` or ``.`` before it dropped).
    """
    from ..io.face_files import escape_braces

    if input_path is None:
        return {}
    path = re.sub(r"[_.-]?\{face\}", "", os.fspath(input_path))
    name = os.path.basename(path)
    stem, ext = os.path.splitext(name)
    values = {"stem": stem, "name": name, "ext": ext.lstrip("."),
              "dir": os.path.dirname(path) or "."}  # fmt: skip
    return {key: escape_braces(value) for key, value in values.items()}


def template_names(template: str) -> list[str]:
    """Names of the ``{variables}`` in a path template (doubled braces are no variable)."""
    return [m.group(1) for m in _VARIABLE.finditer(template) if m.group(1) is not None]


def expand_path(template: str, variables: dict[str, Any],
                user: dict[str, str] | None = None) -> str:  # fmt: skip
    """Replace ``{name}`` in ``template``; ``{face}``/``{level}`` stay; unknown names raise.

    ``user`` variables (resolved by :func:`check_variables`) are replaced first, so their
    values may use the other variables (``out = "{dir}/build"``); the values of ``variables``
    (file names) are taken as they are, never expanded again.
    """
    if user:
        template = _VARIABLE.sub(lambda m: user.get(m.group(1) or "", m.group(0)), template)
    known = {**(user or {}), **variables}

    def substitute(match: re.Match) -> str:
        name = match.group(1)
        if name is None or name in _IO_PLACEHOLDERS:  # an escaped brace, {face}, {level}
            return match.group(0)
        if name not in variables:
            names = ", ".join(f"{{{k}}}" for k in (*known, *_IO_PLACEHOLDERS))
            raise UsageError(f"unknown variable {{{name}}} in path {template!r}; known: {names}")
        return str(variables[name])

    return _VARIABLE.sub(substitute, template)


def check_variables(user: dict[str, Any]) -> dict[str, str]:
    """User variables with their references to each other resolved (as strings).

    A value may use the path variables (:data:`VARIABLES`, ``{face}``, ``{level}``), which stay
    for :func:`expand_path`, and other user variables. Raises UsageError for a name no one
    defines and for a cycle (``a = "{b}"``, ``b = "{a}"``).
    """
    values = {str(k): str(v) for k, v in user.items()}
    resolved: dict[str, str] = {}

    def resolve(name: str, trail: tuple[str, ...]) -> str:
        if name in resolved:
            return resolved[name]
        if name in trail:
            cycle = " -> ".join(f"{{{n}}}" for n in (*trail[trail.index(name) :], name))
            raise UsageError(f"variables refer to each other in a cycle: {cycle}")

        def substitute(match: re.Match) -> str:
            ref = match.group(1)
            if ref is None:  # an escaped brace
                return match.group(0)
            if ref in values:
                return resolve(ref, (*trail, name))
            if ref in VARIABLES or ref in _IO_PLACEHOLDERS:
                return match.group(0)
            known = ", ".join(f"{{{k}}}" for k in (*values, *VARIABLES, *_IO_PLACEHOLDERS))
            raise UsageError(f"variable {name!r} uses unknown variable {{{ref}}}; known: {known}")

        resolved[name] = _VARIABLE.sub(substitute, values[name])
        return resolved[name]

    for name in values:
        resolve(name, ())
    return resolved


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
    """MIP levels of a ``width`` × ``height`` file for ``mips`` as ``Resample`` takes it
    (:func:`envconv.resample.options.check_mips`): 1 without a chain, else at most the full
    round-down chain to 1×1 (:func:`envconv.resample.mips.full_level_count`)."""
    from ..resample.mips import full_level_count
    from ..resample.options import check_mips

    levels = check_mips(mips)[0]
    if levels is None:
        return 1
    full = full_level_count(width, height)
    return full if levels is True else min(levels, full)
