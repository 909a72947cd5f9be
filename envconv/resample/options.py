"""The rules a resample's options follow: the default output size, the automatic sub-sample
count of a mip chain, the filters, and the checks of ``samples``, ``guard`` and ``mips`` (the
one home of those checks: the library, the command line and graph files all call them).

Shared by :mod:`envconv.resample.convert` and :mod:`envconv.resample.mips` (which neither imports the other for
them). Sizes are characteristic sizes N; pitches are those of :func:`envconv.layouts.geometry.horizon_pitch`.
"""

from __future__ import annotations

import math
import numbers

from ..envmap import EnvMap
from ..errors import UsageError
from ..layouts import Layout, get_layout
from ..layouts.conventions import resolve_convention
from ..layouts.geometry import horizon_pitch

__all__ = ["FILTERS", "MAX_SAMPLES", "default_size", "auto_samples", "check_samples", "check_guard",
           "check_mips"]  # fmt: skip

#: Reconstruction filters by name → kernel code.
FILTERS = {"nearest": 0, "bilinear": 1, "bicubic": 2}
MAX_SAMPLES = 32


def default_size(source: EnvMap, to: Layout | str, out_convention=None) -> int:
    """Output N that keeps the source's horizon pitch (see module docstring), or the rule of
    ``out_convention``'s tool: ``pbrt`` makes the square as wide as the lat-long would be."""
    to = get_layout(to)
    if resolve_convention(out_convention, to).size_rule == "latlong-width":
        return 2 * default_size(source, "latlong")
    n = source.size * horizon_pitch(to) / horizon_pitch(source.layout)
    return max(1, int(round(n)))


def auto_samples(source: EnvMap, to: Layout | str, size: int, level_scale: float = 1.0) -> int:
    """Sub-samples per pixel edge for ``samples="auto"`` (see module docstring)."""
    to = get_layout(to)
    pitch_out = horizon_pitch(to) / size * level_scale
    pitch_in = horizon_pitch(source.layout) / source.size
    return int(min(max(round(pitch_out / pitch_in), 1), MAX_SAMPLES))


def check_samples(samples) -> int | None:
    """S for ``samples`` (None for ``"auto"``), or UsageError outside 1 … 64."""
    if samples is None or samples == "auto":
        return None
    try:
        value = int(samples)
    except (TypeError, ValueError):
        raise UsageError(f"samples must be a positive integer or 'auto', got {samples!r}") from None
    if not 1 <= value <= 64:
        raise UsageError(f"samples must be between 1 and 64, got {value}")
    return value


def check_guard(guard) -> int:
    """Guard-ring width in pixels for ``guard`` (not ``"fill"``), or UsageError."""
    try:
        value = int(guard)
    except (TypeError, ValueError):
        raise UsageError(f"guard must be a number of pixels or 'fill', got {guard!r}") from None
    if value < 0 or (isinstance(guard, float) and not math.isclose(guard, value)):
        raise UsageError(f"guard must be a non-negative integer or 'fill', got {guard!r}")
    return value


def check_mips(mips) -> tuple[bool | int | None, bool]:
    """(levels, ggx) of a ``mips`` request, or UsageError.

    ``levels``: None (no chain) for None or False; True (every level down to 1 × 1) for True,
    0, ``"all"``, ``"box"`` and ``"ggx"``; K for K ≥ 1, ``"box:K"`` and ``"ggx:K"``. ``ggx`` is
    True for the GGX-prefiltered chain (``"ggx[:K]"``), False for the box chain.
    """
    if mips is None or mips is False:
        return None, False
    if mips is True:
        return True, False
    if isinstance(mips, str):
        name, colon, count = mips.partition(":")
        if name == "all" and not colon:
            return True, False
        if name in ("box", "ggx") and (not colon or (count.isdigit() and int(count) >= 1)):
            return (int(count) if colon else True), name == "ggx"
        raise UsageError(f"mips must be a number of levels, 'all', 'box[:K]' or 'ggx[:K]' "
                         f"(K >= 1), got {mips!r}")  # fmt: skip
    if isinstance(mips, numbers.Integral) and mips >= 0:
        return (True if mips == 0 else int(mips)), False
    raise UsageError(f"mips must be True or a number of levels, got {mips!r}")
