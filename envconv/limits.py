"""The numbers envconv accepts: one check of every numeric option, at the edge of a run.

A number from the command line, a graph file or a Python caller is checked here before any
file is opened, so that a value no image can have (``--level 1e20``, ``--exposure 1e308``, a
5000-digit size in a graph file) is a usage error naming the option, never an overflow deep in
OpenImageIO, numpy or the native core. :mod:`envconv.cli.options`, the steps of
:mod:`envconv.engine.steps` and graph files (:mod:`envconv.engine.graph`, which also bounds the
nesting and the integers of the whole file with :func:`check_tree`) all call these checks.

The bounds are far beyond any real map and well inside what the libraries can hold:

=================  ================  ==========================================================
option             bound             why
=================  ================  ==========================================================
size N             1 … 2^20          every layout's file (at most 6N + guards wide) keeps the
                                     32-bit width and height image formats store
MIP level          0 … 31            an image 2^31 pixels wide has levels 0 … 31
exposure (stops)   −128 … 128        2^±128 takes any float32 value to 0 or infinity
threads            1 … 1024          more threads than any machine has cores
graph integers     |i| ≤ 2^53        JSON's exact integers (every bound above is far inside)
graph nesting      16 levels         a graph file needs 4 (top table, steps, step, list)
=================  ================  ==========================================================
"""

from __future__ import annotations

import math
import numbers
from typing import Any

from .errors import UsageError

__all__ = ["MAX_SIZE", "MAX_LEVEL", "MAX_STOPS", "MAX_THREADS", "MAX_DEPTH", "MAX_INTEGER",
           "check_size", "check_level", "check_stops", "check_threads", "check_tree", "shown"]  # fmt: skip

MAX_SIZE = 1 << 20
MAX_LEVEL = 31
MAX_STOPS = 128.0
MAX_THREADS = 1024
MAX_DEPTH = 16
MAX_INTEGER = 1 << 53


def shown(value: Any, limit: int = 40) -> str:
    """``repr(value)`` cut to about ``limit`` characters, for a one-line message: a huge
    integer is given by its digit count (its repr alone can be thousands of characters, or
    refused by Python's int-to-text limit)."""
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        bits = int(value).bit_length()
        if bits > 100:
            return f"an integer of about {int(bits * math.log10(2)) + 1} digits"
    try:
        text = repr(value)
    except (ValueError, RecursionError):  # a structure too deep to print
        return f"a {type(value).__name__} too large to show"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _integer(name: str, value: Any, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (numbers.Integral, str, float)):
        raise UsageError(f"{name} must be an integer between {low} and {high}, got {shown(value)}")
    try:
        number = int(value)
    except (TypeError, ValueError, OverflowError):
        raise UsageError(f"{name} must be an integer between {low} and {high}, "
                         f"got {shown(value)}") from None  # fmt: skip
    if isinstance(value, float) and number != value:
        raise UsageError(f"{name} must be an integer between {low} and {high}, got {shown(value)}")
    if not low <= number <= high:
        raise UsageError(f"{name} must be between {low} and {high}, got {shown(number)}")
    return number


def check_size(size: Any) -> int:
    """An output size N (face edge, height, diameter) as an int in 1 … :data:`MAX_SIZE`."""
    return _integer("size", size, 1, MAX_SIZE)


def check_level(level: Any) -> int:
    """A MIP level to read as an int in 0 … :data:`MAX_LEVEL` (None: 0)."""
    return 0 if level is None else _integer("level", level, 0, MAX_LEVEL)


def check_threads(threads: Any) -> int:
    """A thread count as an int in 1 … :data:`MAX_THREADS`."""
    return _integer("threads", threads, 1, MAX_THREADS)


def check_stops(stops: Any, name: str = "exposure") -> float:
    """Exposure in stops as a finite float within ±:data:`MAX_STOPS`."""
    try:
        value = float(stops)
    except (TypeError, ValueError, OverflowError):
        raise UsageError(f"{name} must be a number of stops, got {shown(stops)}") from None
    if not math.isfinite(value) or abs(value) > MAX_STOPS:
        raise UsageError(f"{name} must be a finite number of stops between -{MAX_STOPS:g} and "
                         f"{MAX_STOPS:g}, got {shown(stops)}")  # fmt: skip
    return value


def check_tree(data: Any, max_depth: int = MAX_DEPTH, max_integer: int = MAX_INTEGER) -> None:
    """Refuse parsed TOML/JSON nested more than ``max_depth`` tables and lists deep, or holding
    an integer beyond ±``max_integer``; UsageError naming where (``steps[1].size``: list
    items counted from 1, as graph files' messages count steps).

    Walks the data without recursion, so no input can exhaust the interpreter's stack here.
    """
    stack: list[tuple[Any, str, int]] = [(data, "", 0)]
    while stack:
        value, where, depth = stack.pop()
        if isinstance(value, dict):
            items = [(f"{where}.{k}" if where else str(k), v) for k, v in value.items()]
        elif isinstance(value, list):
            items = [(f"{where}[{i}]", v) for i, v in enumerate(value, 1)]
        else:
            if (isinstance(value, numbers.Integral) and not isinstance(value, bool)
                    and abs(value) > max_integer):  # fmt: skip
                raise UsageError(f"{where}: {shown(value)} is too large (at most "
                                 f"{max_integer} in a graph file)")  # fmt: skip
            continue
        if depth >= max_depth:
            raise UsageError(f"{where or 'the file'}: nested more than {max_depth} deep")
        stack += [(v, w, depth + 1) for w, v in items]
