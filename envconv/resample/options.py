"""The rules a resample's options follow: the default output size (also with a mip chain), the
automatic sub-sample count, the output's channels, the filters, and the checks of
``samples``, ``guard`` and ``mips`` (the one home of those checks: the library, the command
line and graph files all call them).

Shared by :mod:`envconv.resample.convert` and :mod:`envconv.resample.mips` (which neither imports the other for
them). Sizes are characteristic sizes N; pitches are those of :func:`envconv.layouts.geometry.horizon_pitch`.
"""

from __future__ import annotations

import math
import numbers

from ..envmap import EnvMap, alpha_channel
from ..errors import UsageError
from ..layouts import Layout, get_layout
from ..layouts.conventions import resolve_convention
from ..layouts.geometry import horizon_pitch
from ..limits import check_size as bounded_size
from . import kernels

__all__ = ["FILTERS", "choose_filter", "magnifies", "LINEAR_MAGNIFICATION", "ring_past_antipode", "rim_to_mirror_ball", "RIM_SOURCES", "MAX_SAMPLES", "ROUGHNESS_MAPPINGS", "default_size", "auto_samples",
           "check_samples", "check_guard", "check_mips", "check_conventions", "check_roughness",
           "output_channels", "check_size", "check_output", "output_layout"]  # fmt: skip

#: Reconstruction filters by name → kernel code; the first is the default.
FILTERS = {
    "area": kernels.AREA_FILTER,
    "bilinear": kernels.FILTER_BILINEAR,
    "bicubic": kernels.FILTER_BICUBIC,
    "nearest": kernels.FILTER_NEAREST,
}
MAX_SAMPLES = 32
#: The area filter integrates its linear reconstruction (src/core/area_linear.h) instead of the
#: box when the output's mean pixel solid angle is below the source's mean texel solid angle
#: divided by this (see :func:`magnifies` and docs/native-core.md for the measurements).
LINEAR_MAGNIFICATION = 1.5
#: How a GGX chain's levels get their roughness (:func:`envconv.resample.ibl.roughness_levels`).
ROUGHNESS_MAPPINGS = ("gltf", "filament", "unreal")


def default_size(source: EnvMap, to: Layout | str, out_convention=None, mips=None,
                 guard=0) -> int:  # fmt: skip
    """Output N when none is given: the N that keeps the source's angular pixel pitch along
    the horizon (``source N × pitch(source) / pitch(to)``, pitches of
    :func:`envconv.layouts.geometry.horizon_pitch`: a 2048 × 1024 lat-long gives cube faces
    of 559), or the rule of ``out_convention``'s tool (``pbrt`` makes the square as wide as
    the lat-long would be).

    With a MIP chain (``mips`` as :func:`check_mips` takes it) N is then rounded so that every
    level holds whole cells: N + 2G (``guard``) becomes the nearest power of two for a full
    chain (cells halve exactly until they are one texel: 559 becomes 512), or the nearest
    multiple of 2^(K − 1) for K levels. A given size is never changed."""
    to = get_layout(to)
    if resolve_convention(out_convention, to).size_rule == "latlong-width":
        n = 2 * default_size(source, "latlong")
    else:
        n = max(1, int(round(source.size * horizon_pitch(to) / horizon_pitch(source.layout))))
    levels = check_mips(mips)[0]
    if levels is None:
        return n
    guard = 0 if guard == "fill" else check_guard(guard)
    cell = n + 2 * guard
    if levels is True:
        low = 1 << (cell.bit_length() - 1)
        cell = low if cell * cell < 2 * low * low else 2 * low  # nearer in log2; ties go up
        while cell - 2 * guard < 1:
            cell *= 2
        return cell - 2 * guard
    step = 1 << (levels - 1)
    cell = max(step, round(cell / step) * step)
    while cell - 2 * guard < 1:
        cell += step
    return cell - 2 * guard


def check_size(size) -> tuple[int | None, int | None]:
    """(N, width) of ``size``: None (the default), N, ``"N"``, ``"WxH"`` or (W, H); width is
    None unless a W × H size was given (a perspective view's, N being its height). UsageError
    for anything else, and for a number beyond :data:`envconv.limits.MAX_SIZE`."""
    if size is None:
        return None, None
    if isinstance(size, str):
        parts = size.strip().lower().replace("×", "x").split("x")
        if len(parts) not in (1, 2) or not all(p.strip().isdigit() for p in parts):
            raise UsageError(f"size must be N or WxH in pixels, got {size!r}")
        size = tuple(int(p) for p in parts) if len(parts) == 2 else int(parts[0])
    if isinstance(size, (tuple, list)):
        if len(size) != 2 or not all(isinstance(v, numbers.Integral) and v >= 1 for v in size):
            raise UsageError(f"size must be N or (W, H), positive integers, got {size!r}")
        return bounded_size(size[1]), bounded_size(size[0])
    if isinstance(size, numbers.Integral) and not isinstance(size, bool) and size >= 1:
        return bounded_size(size), None
    raise UsageError(
        f"size must be a positive integer (or WxH for a perspective view), got {size!r}"
    )


def check_output(to: Layout | str, size=None, fov=None, yaw=None, pitch=None,
                 roll=None) -> Layout:  # fmt: skip
    """``to`` configured with the view options and a W × H ``size`` (see :func:`output_layout`),
    for checking them before any source is read; UsageError for one the layout does not take."""
    to = get_layout(to)
    n, width = check_size(size)
    if width is not None and to.configurer is None:
        raise UsageError(f"{to.name} takes --size N, not {width}x{n}; W x H is a perspective "
                         "view's size")  # fmt: skip
    view = {"fov": fov, "yaw": yaw, "pitch": pitch, "roll": roll}
    return to.configure(**view, width=width, height=n if width is not None else None)


def output_layout(source: EnvMap, to: Layout | str, size=None, fov=None, yaw=None, pitch=None,
                  roll=None, out_convention=None, mips=None,
                  guard=0) -> tuple[Layout, int]:  # fmt: skip
    """The output layout with its view options (:meth:`envconv.layouts.base.Layout.configure`:
    ``fov``, ``yaw``, ``pitch``, ``roll``) and its size N: ``size``, or :func:`default_size`
    (with ``mips`` and ``guard``).
    A W × H ``size`` is a perspective view's own (N is its height); a view's width otherwise
    follows from its aspect. UsageError for an option the layout does not take."""
    to = get_layout(to)
    view = {"fov": fov, "yaw": yaw, "pitch": pitch, "roll": roll}
    layout = check_output(to, size, **view)
    n, width = check_size(size)
    if n is None:
        n = default_size(source, layout, out_convention, mips=mips, guard=guard)
    if layout.configurer is not None and width is None:
        layout = to.configure(**view, width=layout.content_width(n), height=n)
    return layout, n


def auto_samples(source: EnvMap, to: Layout | str, size: int, level_scale: float = 1.0) -> int:
    """Sub-samples per pixel edge for ``samples="auto"`` (see module docstring)."""
    to = get_layout(to)
    pitch_out = horizon_pitch(to) / size * level_scale
    pitch_in = horizon_pitch(source.layout) / source.size
    return int(min(max(round(pitch_out / pitch_in), 1), MAX_SAMPLES))


def choose_filter(requested: str | None) -> str:
    """The filter a conversion uses: ``requested``, or without one the area filter; UsageError
    for an unknown name.

    The area filter takes every case: a partial view as input (the part of a footprint outside
    the view is a hole, :mod:`envconv.resample.partial`); a guard ring around a whole-sphere
    layout (its cells the area filter's, its ring what a GPU reads across their edge:
    :func:`envconv.resample.convert.convert`); and a guard ring (or ``fill``) around a partial
    view, whose ring pixels are more of the view: each the exact
    mean over its own footprint under the continued mapping (the image plane extended, the
    fisheye's radial formula continued), with alpha 0. Only a fisheye ring that reaches the
    point behind the view (:func:`ring_past_antipode`) has no footprints of its own there: its
    ring is point-sampled, the view's pixels still exact."""
    if requested is not None and requested not in FILTERS:
        raise UsageError(f"unknown filter {requested!r}; choose one of {', '.join(FILTERS)}")
    return requested or "area"


def ring_past_antipode(to: Layout, size: int | None, guard) -> bool:
    """True when ``to`` is a partial fisheye whose guard ring (``guard`` pixels around size N,
    or ``"fill"``: the square's corners, radius √2) reaches θ = 180°, the point behind its
    view: there the continued map folds the whole circle onto that one direction and back, and
    the area filter's footprints would not be the ring pixels' own. Without ``size`` a ring
    of G pixels is taken to reach it (a size not known yet: the safe answer)."""
    if guard in (0, None) or not to.partial or to.family != kernels.FAMILY_FISHEYE:
        return False
    if guard == "fill":
        radius = math.sqrt(2.0)
    else:
        radius = math.inf if size is None else 1.0 + 2.0 * check_guard(guard) / size
    half = float(to.params[0])
    return half * radius >= math.pi


#: Sources whose whole rim is one direction (−Z): the area filter cannot yet take them into a
#: mirror ball, whose own rim is −Z too (a one-texel sun there moves by up to 1 %): such a
#: conversion goes through an exact lat-long 1.5 times finer than the source at the horizon.
RIM_SOURCES = ("sphere", "angular")


def _mean_pixel_solid_angle(layout: Layout, size: int) -> float:
    """Mean solid angle (sr) of a valid pixel of ``layout`` at size N = ``size``: what it
    covers (4π; a partial view's own, summed over its pixels at N = 64, since it does not depend
    on N) over its valid pixels."""
    count = layout.n_faces * layout.content_width(size) * size * (math.pi / 4 if layout.disk else 1)
    if not layout.partial:
        return 4 * math.pi / count
    from ..layouts.geometry import pixel_solid_angles

    return float(pixel_solid_angles(layout, 64, 0, samples=4).sum()) / count


def magnifies(source: EnvMap, to: Layout | str, size: int) -> bool:
    """True when a conversion of ``source`` to ``to`` at size ``size`` magnifies: the output's
    mean pixel solid angle is below the source's mean texel solid angle divided by
    :data:`LINEAR_MAGNIFICATION`. The area filter then integrates its conservative
    piecewise-linear reconstruction rather than the box, which would show texel blocks."""
    to = get_layout(to)
    texel = _mean_pixel_solid_angle(source.layout, source.size)
    return _mean_pixel_solid_angle(to, size) * LINEAR_MAGNIFICATION < texel


def rim_to_mirror_ball(envmap: EnvMap, to: Layout, filter: str) -> bool:
    """True when ``envmap`` → ``to`` takes the lat-long step of RIM_SOURCES."""
    return (filter == "area" and to.name == "sphere" and envmap.layout.name in RIM_SOURCES
            and envmap.valid is None and not envmap.parts)  # fmt: skip


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


def output_channels(channels, alpha: bool) -> tuple[str, ...]:
    """The channels of a resample's output: the source's, every one resampled, with ``A``
    appended when ``alpha`` asks for coverage and the source has no alpha channel (an
    existing one is overwritten with the coverage)."""
    channels = tuple(channels)
    if alpha and alpha_channel(channels) is None:
        return (*channels, "A")
    return channels


def check_conventions(to: Layout | str, out_convention=None, mips=None, source=None,
                      in_convention=None, guard=0):  # fmt: skip
    """(in, out) :class:`~envconv.layouts.conventions.Convention` of a resample to ``to`` from
    a ``source`` layout (None: not known yet, the input convention is not resolved).

    Raises LayoutError for a convention named for a layout it does not apply to
    (:func:`~envconv.layouts.conventions.resolve_convention`; the engine refuses it as bad
    usage before any pixel is read), and UsageError for an output convention that moves
    cells with a mip chain (its levels would mix moved cells) or one on another sample grid
    with a mip chain or a guard ring (:func:`envconv.resample.regrid.check_output_grid`)."""
    from .regrid import check_output_grid

    cout = resolve_convention(out_convention, to)
    cin = None if source is None else resolve_convention(in_convention, source)
    chain = check_mips(mips)[0] is not None
    check_output_grid(cout, chain, guard)
    if cout.remap is not None and chain:
        raise UsageError(f"out_convention {cout.name} moves cells; it cannot be used with mips")
    return cin, cout


def check_roughness(roughness) -> str | list[float]:
    """The roughness of a GGX chain's levels: a mapping name (:data:`ROUGHNESS_MAPPINGS`;
    None gives ``"gltf"``) or the perceptual roughness of levels 1, 2, … each in [0, 1], as a
    list of numbers or the command line's ``"0.1,0.4,1"``; UsageError otherwise. How many
    values a chain needs is checked once its level count is known
    (:func:`envconv.resample.ibl.roughness_levels`)."""
    if roughness is None:
        return "gltf"
    if isinstance(roughness, str) and roughness in ROUGHNESS_MAPPINGS:
        return roughness
    expected = (f"roughness must be one of {', '.join(ROUGHNESS_MAPPINGS)} or a list of numbers "
                "in [0, 1] (comma-separated on the command line)")  # fmt: skip
    if isinstance(roughness, str):
        parts: list = [p for p in roughness.split(",") if p.strip()]
    elif isinstance(roughness, (list, tuple)):
        parts = list(roughness)
        if not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in parts):
            raise UsageError(f"{expected}, got {roughness!r:.60}")
    else:
        raise UsageError(f"{expected}, got {roughness!r:.60}")
    try:
        values = [float(v) for v in parts]
    except (TypeError, ValueError, OverflowError):
        raise UsageError(f"{expected}, got {roughness!r:.60}") from None
    if not values or not all(0.0 <= v <= 1.0 for v in values):
        raise UsageError(f"{expected}, got {roughness!r:.60}")
    return values
