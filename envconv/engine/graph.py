"""Graph files: a pipeline (:mod:`envconv.engine.pipeline`) written down as TOML or JSON.

A graph file holds the same steps as a shell chain, one table per step, in order::

    inputs = ["hdri/*.exr"]          # optional: files, globs or directories; one job each
    [vars]                           # optional: user variables for paths, here {out}
    out = "build"

    [[steps]]
    step = "resample"                # read, rotate, exposure, colorspace, resample, write
    to = "cube-vcross"
    size = 512

    [[steps]]
    step = "write"
    path = "{out}/{stem}_{layout}.exr"

Keys are the keyword arguments of the library call a step feeds (``to``, ``size``, ``samples``,
``filter``, ``guard``, ``alpha``, ``mips`` for resample; ``path``, ``layout``/``from``, ``level``
for read; ``path``, ``bit_depth`` … for write); dashes may stand for underscores. With
``inputs``, the steps are a recipe run once per input (a leading ``read`` is then optional and
takes no path). Relative paths (inputs, read and write paths) are relative to the graph file.
The file is checked completely before any pixel is read; every error names the file, the step
and the key.
"""

from __future__ import annotations

import inspect
import json
import math
import os
from dataclasses import dataclass, field
from typing import Any

from .. import io
from ..color.prepare import FIX_MODES
from ..errors import EnvconvError, UsageError
from ..layouts import get_layout
from ..limits import (
    MAX_DEPTH,
    MAX_LEVEL,
    MAX_SIZE,
    MAX_STOPS,
    check_level,
    check_stops,
    check_tree,
    shown,
)
from ..resample.convert import FILTERS, convert
from ..resample.options import check_guard, check_mips, check_roughness, check_samples, check_size
from .pipeline import Colorspace, Exposure, Pipeline, Read, Resample, Rotate, Step, Write
from .steps import PREPARE_OPTIONS, check_variables

__all__ = ["Graph", "load_graph", "parse_graph", "STEP_KEYS", "CHECKS"]

_TOP_KEYS = {"version", "inputs", "vars", "steps"}
_ALIASES = {
    "read": {"from": "layout"},
    "colorspace": {"to": "dst", "from": "src", "ocio_config": "config"},
}


def _signature_keys(fn, *skip: str) -> set[str]:
    return {
        name
        for name, p in inspect.signature(fn).parameters.items()
        if name not in skip and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
    }


def _step_keys() -> dict[str, set[str]]:
    # Derived from the library signatures, so options added there are accepted here too;
    # ``threads`` is the run's setting (ENVCONV_THREADS, --threads), not the recipe's.
    return {
        "read": {"path"} | _signature_keys(io.read, "path", "threads") | set(PREPARE_OPTIONS),
        "rotate": {"angles", "yaw", "pitch", "roll"},
        "exposure": {"stops"},
        "colorspace": {"dst", "src", "config"},
        "resample": _signature_keys(convert, "envmap", "threads"),
        "write": {"path", "makedirs", "preview", "no_clobber"}
        | _signature_keys(io.write, "envmap", "path", "warnings"),
    }


STEP_KEYS = _step_keys()
_CLASSES = {"read": Read, "rotate": Rotate, "exposure": Exposure, "colorspace": Colorspace,
            "resample": Resample, "write": Write}  # fmt: skip


@dataclass
class Graph:
    """A loaded graph file: its path, input patterns, user variables and steps."""

    path: str
    steps: list[Step]
    inputs: list[str] = field(default_factory=list)
    variables: dict[str, str] = field(default_factory=dict)

    @property
    def pipeline(self) -> Pipeline:
        return Pipeline(self.steps, self.variables)


def load_graph(path: str | os.PathLike, recipe: bool | None = None) -> Graph:
    """Read and validate a graph file (``.toml`` or ``.json``); raise UsageError naming the
    file, the step and the key of the first problem.

    ``recipe=True`` validates the steps as a per-input recipe even when the file lists no
    ``inputs`` (``envconv batch INPUTS --graph FILE``); by default that follows ``inputs``.
    """
    path = os.fspath(path)
    try:
        with open(path, "rb") as handle:
            raw = handle.read()
    except OSError as exc:
        raise UsageError(f"cannot read graph file {path}: {exc.strerror or exc}") from None
    if path.lower().endswith(".json"):
        try:
            data = _parsed(path, lambda: json.loads(raw.decode("utf-8")))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise UsageError(f"{path}: not valid JSON: {exc}") from None
    else:
        data = _parse_toml(path, raw)
    return parse_graph(data, path, recipe)


def _parsed(path: str, parse) -> Any:
    """``parse()``, with what no parser survives as a usage error: nesting deeper than the
    interpreter's stack, and integers longer than Python turns into numbers (4300 digits)."""
    try:
        return parse()
    except RecursionError:
        raise UsageError(f"{path}: nested too deeply (at most {MAX_DEPTH} levels)") from None
    except ValueError as exc:
        if "digits" not in str(exc) or isinstance(exc, json.JSONDecodeError):
            raise
        raise UsageError(f"{path}: a number is too large (thousands of digits)") from None


def _parse_toml(path: str, raw: bytes) -> Any:
    try:
        import tomllib
    except ImportError:  # Python 3.10
        try:
            import tomli as tomllib  # type: ignore[no-redef]
        except ImportError:
            raise UsageError(f"{path}: reading TOML needs Python ≥ 3.11 or tomli; "
                             "or write the graph as JSON") from None  # fmt: skip
    try:
        return _parsed(path, lambda: tomllib.loads(raw.decode("utf-8")))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise UsageError(f"{path}: not valid TOML: {exc}") from None


def parse_graph(data: Any, path: str = "<graph>", recipe: bool | None = None) -> Graph:
    """Build a :class:`Graph` from parsed TOML/JSON data (see the module docstring)."""
    if not isinstance(data, dict):
        raise UsageError(f"{path}: expected a table at the top level")
    try:
        check_tree(data)
    except UsageError as exc:
        raise UsageError(f"{path}: {exc}") from None
    for key in data:
        if key not in _TOP_KEYS:
            raise UsageError(f"{path}: unknown top-level key {key!r}; known: "
                             + ", ".join(sorted(_TOP_KEYS)))  # fmt: skip
    if data.get("version", 1) != 1:
        raise UsageError(f"{path}: key 'version': only version 1 exists, got {data['version']!r}")
    base = os.path.dirname(os.path.abspath(path))
    inputs = data.get("inputs", [])
    if isinstance(inputs, str):
        inputs = [inputs]
    if not isinstance(inputs, list) or not all(isinstance(i, str) and i for i in inputs):
        raise UsageError(f"{path}: key 'inputs': expected a list of paths or globs")
    variables = data.get("vars", {})
    if not isinstance(variables, dict) or not all(
        isinstance(v, (str, int, float)) for v in variables.values()
    ):
        raise UsageError(f"{path}: key 'vars': expected a table of strings")
    try:
        check_variables(variables)
    except UsageError as exc:
        raise UsageError(f"{path}: key 'vars': {exc}") from None
    steps_data = data.get("steps")
    if not isinstance(steps_data, list) or not steps_data:
        raise UsageError(f"{path}: key 'steps': expected at least one [[steps]] table")
    steps = [_parse_step(path, index, item, base) for index, item in enumerate(steps_data, 1)]
    graph = Graph(path, steps, [_rebase(i, base) for i in inputs],
                  {k: str(v) for k, v in variables.items()})  # fmt: skip
    try:
        recipe = bool(inputs) if recipe is None else recipe
        graph.pipeline.validate(input="input.exr" if recipe else None, require_writes=True)
    except UsageError as exc:
        raise UsageError(f"{path}: {exc}") from None
    return graph


def _rebase(value: str, base: str) -> str:
    """Paths relative to the graph file; a path starting with a variable is left alone."""
    if os.path.isabs(value) or value.startswith("{"):
        return value
    return os.path.join(base, value)


def _parse_step(path: str, index: int, item: Any, base: str) -> Step:
    if not isinstance(item, dict):
        raise UsageError(f"{path}: step {index}: expected a table")
    kind = item.get("step")
    where = f"{path}: step {index} ({kind})"
    if kind not in STEP_KEYS:
        raise UsageError(f"{path}: step {index}: key 'step': expected one of "
                         f"{', '.join(STEP_KEYS)}, got {kind!r}")  # fmt: skip
    params: dict[str, Any] = {}
    for raw_key, value in item.items():
        if raw_key == "step":
            continue
        key = raw_key.replace("-", "_")
        key = _ALIASES.get(kind, {}).get(key, key)
        if key not in STEP_KEYS[kind]:
            raise UsageError(f"{where}: unknown key {raw_key!r}; known: "
                             + ", ".join(sorted(STEP_KEYS[kind])))  # fmt: skip
        problem = _check_value(key, value)
        if problem:
            raise UsageError(f"{where}: key {raw_key!r}: {problem}")
        params[key] = value
    if kind == "read" and isinstance(params.get("path"), str):
        params["path"] = _rebase(params["path"], base)
    if kind == "write":
        params["base"] = base
    try:
        return _CLASSES[kind](**params)
    except TypeError as exc:
        raise UsageError(f"{where}: {_missing(exc)}") from None
    except EnvconvError as exc:
        raise UsageError(f"{where}: {exc}") from None


def _missing(exc: TypeError) -> str:
    text = str(exc)
    if "missing" in text and "'" in text:
        return "missing key " + text[text.index("'") :]
    return text


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _text(value: Any) -> str | None:
    return None if isinstance(value, str) and value else "a non-empty string"


def _choice(*choices: str):
    return lambda value: None if value in choices else "one of " + ", ".join(choices)


def _layout(value: Any) -> str | None:
    if not isinstance(value, str):
        return "a layout name (see envconv layouts)"
    try:
        get_layout(value)
    except EnvconvError as exc:
        return f"a layout name ({exc})"
    return None


def _convention(value: Any) -> str | None:
    from ..errors import LayoutError
    from ..layouts.conventions import resolve_convention
    from ..layouts.facesets import is_face_set

    expected = "a convention name, a face set or an axis remap like '-x,z,y'"
    if not isinstance(value, str) or not value:
        return expected
    if is_face_set(value):
        return None
    try:
        resolve_convention(value, "latlong")
    except LayoutError:  # a known preset of other layouts
        return None
    except EnvconvError as exc:
        return f"{expected} ({exc})"
    return None


def _passes(check, value: Any) -> bool:
    """Whether one of :mod:`envconv.resample.options`'s checks (the one home of the rule) takes it."""
    try:
        check(value)
    except EnvconvError:
        return False
    return True


def _compression(value: Any) -> str | None:
    from ..io.formats import COMPRESSIONS

    names = sorted({c.rstrip(":") for codecs in COMPRESSIONS.values() for c in codecs})
    if isinstance(value, str) and value.partition(":")[0].lower() in names:
        return None
    return "a compression name (" + ", ".join(names) + "), optionally with :LEVEL"


def _face_set(value: Any) -> str | None:
    from ..layouts.facesets import is_face_set

    return (
        None
        if is_face_set(value)
        else "a face set name (quake, unity-6sided, threejs, godot, unreal)"
    )


def _angles(value: Any) -> str | None:
    if isinstance(value, str) or (isinstance(value, list) and len(value) == 3
                                  and all(_is_number(v) for v in value)):  # fmt: skip
        return None
    return "'YAW,PITCH,ROLL' or a list of three numbers"


def _roughness(value: Any) -> str | None:
    if _passes(check_roughness, value):
        return None
    return "gltf, filament, unreal or a list of numbers in [0, 1]"


_BOOL = lambda value: None if isinstance(value, bool) else "true or false"  # noqa: E731
_NUMBER = lambda value: None if _is_number(value) else "a finite number"  # noqa: E731
_STOPS = lambda value: (  # noqa: E731
    None
    if _is_number(value) and _passes(check_stops, value)
    else f"a number of stops in ±{MAX_STOPS:g}"
)

#: What each key of a step takes: a function returning None, or what was expected.
CHECKS: dict[str, Any] = {
    "path": _text, "preview": _text, "dst": _text, "src": _text, "config": _text,
    "ocio_config": _text, "input_colorspace": _text, "output_colorspace": _text,
    "axes": _text, "to": _layout, "layout": _layout,
    "size": lambda v: None if (_is_int(v) or isinstance(v, (str, list))) and _passes(check_size, v)
    else f"an integer in 1..{MAX_SIZE}, or 'WxH'",
    "fov": lambda v: None if _is_number(v) or isinstance(v, str) or (
        isinstance(v, list) and len(v) == 2 and all(_is_number(x) for x in v)) else
    "degrees: a number, 'H,V' or [H, V]",
    "level": lambda v: None if _is_int(v) and _passes(check_level, v) else f"an integer in 0..{MAX_LEVEL}",
    "part": lambda v: None if (_is_int(v) and v >= 0) or (isinstance(v, str) and v) else
    "a part name or index",
    "samples": lambda v: None if v == "auto" or _is_int(v) and _passes(check_samples, v) else
    "1..64 or 'auto'",
    "filter": _choice(*FILTERS),
    "guard": lambda v: None if v == "fill" or _is_int(v) and _passes(check_guard, v) else
    "a non-negative integer or 'fill'",
    "alpha": _BOOL, "makedirs": _BOOL, "dither": _BOOL, "irradiance": _BOOL,
    "clamp_negative": _BOOL, "no_clobber": _BOOL,
    "mips": lambda v: None if isinstance(v, (bool, int, str)) and _passes(check_mips, v) else
    "true, false, a number of levels, 'all', 'box[:K]' or 'ggx[:K]'",
    "roughness": _roughness, "up": _choice("y", "z"),
    "in_convention": _convention, "out_convention": _convention, "faces": _face_set,
    "stops": _STOPS, "yaw": _NUMBER, "pitch": _NUMBER, "roll": _NUMBER, "exposure": _STOPS,
    "angles": _angles, "rotate": _angles,
    "bit_depth": _choice("half", "float", "uint8", "uint16"),
    "compression": _compression, "fix_nonfinite": _choice(*FIX_MODES),
}  # fmt: skip


def _check_value(key: str, value: Any) -> str | None:
    """A problem with ``value`` for ``key`` (``expected …, got …``), or None."""
    expected = CHECKS[key](value)
    return None if expected is None else f"expected {expected}, got {shown(value)}"
