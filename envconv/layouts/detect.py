"""Telling layouts apart: from metadata first, then from the aspect ratio.

Order: the ``envconv:layout`` tag (with ``envconv:guard``), then OpenEXR's ``envmap`` attribute
(``latlong`` → latlong, ``cube`` → cube-exr; OpenImageIO reports it as ``textureformat``
"LatLong Environment" or "CubeFace Environment"), then the aspect ratio. Aspects that only one
layout has are guessed: 3:4 cube-vcross, 4:3 cube-hcross, 6:1 cube-hstrip.
Shared aspects are refused with a message naming the candidates, except 2:1: a 2:1 image is a
lat-long unless it is black outside two inscribed disks, which is what an untagged packed
paraboloid looks like; then it is ambiguous too. 1:1 (sphere, angular, octahedral, equal-area
or fisheye), 1:6 (cube-vstrip or cube-exr) and 3:2 (tennisball or eac, the equi-angular cube
of YouTube and ffmpeg) always need ``--from``; a perspective view, whose aspect is its own, is
known only by its tag or ``--from``. No pixel test tells the
square layouts apart: the two octahedral squares fill every pixel with the same kind of sky, and
pbrt-v4's ``imgtool makeequiarea`` writes no attribute that names its layout, so a pbrt file
is read with ``--from equal-area --in-convention pbrt``.

:func:`find_layout` answers without raising (``envconv info`` reports "unknown" with the
candidates and why); :func:`place_image` is what reading uses: the layout (given or detected),
guard and size, or a :class:`~envconv.errors.LayoutError` saying which sizes would fit.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from ..errors import LayoutError, UsageError
from . import LAYOUTS, Layout, get_layout
from .view import VIEW_TAG, parse_view_text

__all__ = ["find_layout", "place_image", "misfit_message", "tagged_guard", "Found"]

_UNIQUE_ASPECTS = {
    (3, 4): "cube-vcross",
    (4, 3): "cube-hcross",
    (6, 1): "cube-hstrip",
}
_SHARED_ASPECTS = {
    (1, 1): ("sphere", "angular", "octahedral", "equal-area", "fisheye"),
    (1, 6): ("cube-vstrip", "cube-exr"),
    (3, 2): ("tennisball", "eac"),
}


#: Layouts whose aspect is their own (a perspective view's W × H): never guessed from it.
_OWN_ASPECT = ("perspective",)


class Found(NamedTuple):
    """What detection found: ``layout`` (None when it cannot tell), ``guard``, the
    ``candidates`` it weighed, and ``reason``: how it knows, or why it cannot tell."""

    layout: Layout | None
    guard: int
    candidates: tuple[str, ...]
    reason: str


def tagged_guard(metadata: dict[str, Any]) -> int:
    """The guard ring G a file's ``envconv:guard`` tag records (0 when untagged)."""
    return int(metadata.get("envconv:guard", 0) or 0)


def find_layout(
    width: int, height: int, metadata: dict[str, Any], pixels: np.ndarray | None = None
) -> Found:
    """The layout of a ``width`` × ``height`` image with this metadata, never raising."""
    tag = metadata.get("envconv:layout")
    guard = tagged_guard(metadata)
    if tag in LAYOUTS:
        return Found(get_layout(tag), guard, (tag,), f"envconv:layout tag {tag}")
    envmap = str(metadata.get("envmap", "")).lower()
    texture = str(metadata.get("textureformat", "")).lower()
    if envmap == "latlong" or texture == "latlong environment":
        return Found(get_layout("latlong"), 0, ("latlong",), "OpenEXR envmap attribute latlong")
    if envmap == "cube" or texture == "cubeface environment":
        return Found(get_layout("cube-exr"), 0, ("cube-exr",), "OpenEXR envmap attribute cube")
    return _from_aspect(width, height, pixels)


def _from_aspect(width: int, height: int, pixels: np.ndarray | None) -> Found:
    for (aw, ah), name in _UNIQUE_ASPECTS.items():
        if width * ah == height * aw:
            return Found(get_layout(name), 0, (name,), f"aspect {aw}:{ah}")
    for (aw, ah), names in _SHARED_ASPECTS.items():
        if width * ah == height * aw:
            return Found(None, 0, names, (
                f"input is {width}x{height}: aspect {aw}:{ah} could be {_alternatives(names)} "
                "and the file has no layout metadata; pass --from"))  # fmt: skip
    if width == 2 * height:
        if pixels is not None and _black_outside_two_disks(pixels):
            return Found(None, 0, ("latlong", "paraboloid"), (
                f"input is {width}x{height} and black outside two disks: it could be latlong or "
                "paraboloid; pass --from"))  # fmt: skip
        return Found(get_layout("latlong"), 0, ("latlong", "paraboloid"), "aspect 2:1")
    return Found(None, 0, (), (
        f"input is {width}x{height}, which matches no layout's aspect ({_aspect_list()}); "
        "crop it to one of them, or pass --from to see which sizes a layout takes"))  # fmt: skip


def _aspect_list() -> str:
    """'2:1 latlong or paraboloid, 3:4 cube-vcross, …' for every single-file layout."""
    by_aspect: dict[str, list[str]] = {}
    for layout in LAYOUTS.values():
        if not layout.multi_file and layout.name not in _OWN_ASPECT:
            w, h = layout.image_size(1, 0)
            by_aspect.setdefault(f"{w // math.gcd(w, h)}:{h // math.gcd(w, h)}", []).append(
                layout.name
            )
    return ", ".join(f"{aspect} {' or '.join(names)}" for aspect, names in by_aspect.items())


def _alternatives(names) -> str:
    return " or ".join(names) if len(names) < 3 else f"{', '.join(names[:-1])} or {names[-1]}"


def _black_outside_two_disks(pixels: np.ndarray) -> bool:
    """Whether every colour value outside the two inscribed disks is 0 (and there is such a
    value), tested a block of rows at a time: the mask of a whole map would be a float64
    plane, 2/3 of an RGB float32 source."""
    height, width = pixels.shape[:2]
    n = height
    y = (np.arange(n) + 0.5) / n * 2 - 1
    x = (np.arange(width) + 0.5) / n
    x = np.where(x < 1.0, x * 2 - 1, (x - 1.0) * 2 - 1)
    colour = min(3, pixels.shape[2])
    rows = max(1, (1 << 20) // max(1, width))
    found = False
    for y0 in range(0, n, rows):
        outside = (x[None, :] ** 2 + y[y0 : y0 + rows, None] ** 2) > 1.0 + 4.0 / n
        values = pixels[y0 : y0 + rows][outside][..., :colour]
        if np.any(values != 0):
            return False
        found = found or bool(values.size)
    return found


def _ratio(w: int, h: int) -> str:
    """'width = 2 × height' for a w:h image; 'width:height = 3:4' when neither divides."""
    g = math.gcd(w, h)
    w, h = w // g, h // g
    if (w, h) == (1, 1):
        return "width = height"
    if h == 1:
        return f"width = {w} × height"
    if w == 1:
        return f"height = {h} × width"
    return f"width:height = {w}:{h}"


def misfit_message(
    layout: Layout, width: int, height: int, guard: int = 0, origin: str = "given by --from"
) -> str:
    """Why a ``width`` × ``height`` image is not ``layout`` (which ``origin`` named), which
    sizes would be, and what to do."""
    w1, h1 = layout.image_size(1, 0)
    if guard:
        a = "N" if layout.aspect == 1 else f"{layout.aspect}N"
        grid = (
            f"{layout.columns} × {layout.rows} cells of "
            if layout.columns * layout.rows > 1
            else ""
        )
        rule = f"{grid}({a}+{2 * guard}) × (N+{2 * guard}) pixels with its {guard}-pixel guard"
    else:
        rule = _ratio(w1, h1)
    sizes = []
    for n in ((height - layout.rows * 2 * guard) / h1, (width - layout.columns * 2 * guard) / w1):
        if n >= 1 and n == int(n):
            fit = layout.image_size(int(n), guard)
            if fit != (width, height) and f"{fit[0]}x{fit[1]}" not in sizes:
                sizes.append(f"{fit[0]}x{fit[1]}")
    would = f" ({' or '.join(sizes)} would be)" if sizes else ""
    others = find_layout(width, height, {}, None)
    fits = (others.layout.name,) if others.layout is not None else others.candidates
    aspect = f"its aspect fits {' or '.join(fits)}" if fits else "its aspect fits no layout"
    return (f"{layout.name} ({origin}) needs {rule}, and {width}x{height} is not{would}; "
            f"crop or resize it, or pass --from with the layout it is in ({aspect})")  # fmt: skip


def _aim(layout: Layout, metadata: dict[str, Any], width: int, height: int, guard: int) -> Layout:
    """An aimed layout (fisheye, perspective) with the view its file records (``envconv:view``,
    when the file is tagged as this layout; else the layout's defaults) and, for a
    perspective view, the image's own aspect."""
    options: dict[str, Any] = {}
    if metadata.get("envconv:layout") == layout.name and VIEW_TAG in metadata:
        try:
            options = parse_view_text(metadata[VIEW_TAG])
            layout = layout.configure(**options)
        except UsageError as exc:
            raise LayoutError(f"the file's {exc}; pass --from with another layout") from None
    cw, ch = width // layout.columns - 2 * guard, height // layout.rows - 2 * guard
    if cw >= 1 and ch >= 1 and layout.content_width(ch) != cw:
        try:
            layout = layout.configure(fov=options.get("fov"), width=cw, height=ch)
        except UsageError:  # a size the layout cannot take: size_from_image says why
            pass
    return layout


def place_image(
    width: int,
    height: int,
    metadata: dict[str, Any],
    layout: str | Layout | None = None,
    pixels: np.ndarray | None = None,
    level: int = 0,
) -> tuple[Layout, int, int]:
    """(layout, guard, N) of a ``width`` × ``height`` image (MIP ``level`` of its file): the
    given ``layout`` or the detected one. Raises LayoutError when it cannot be placed.

    The guard is the file's ``envconv:guard`` when it is the layout the file is tagged with,
    halved per MIP level (``G >> k``)."""
    if layout is None:
        detected = find_layout(width, height, metadata, pixels)
        if detected.layout is None:
            raise LayoutError(detected.reason)
        found, guard = detected.layout, detected.guard
        origin = f"named by its {detected.reason.rsplit(' ', 1)[0]}"  # "… envconv:layout tag"
    else:
        found = get_layout(layout)
        guard = tagged_guard(metadata) if metadata.get("envconv:layout") == found.name else 0
        origin = "given by --from"
    guard >>= level + int(metadata.get("envconv:level", 0) or 0)  # a level's guard is G >> k
    if found.configurer is not None:
        found = _aim(found, metadata, width, height, guard)
    try:
        size = found.size_from_image(width, height, guard)
    except LayoutError:
        raise LayoutError(misfit_message(found, width, height, guard, origin)) from None
    return found, guard, size
