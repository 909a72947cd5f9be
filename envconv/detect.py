"""Telling layouts apart: from metadata first, then from the aspect ratio.

Order: the ``envconv:layout`` tag (with ``envconv:guard``), then OpenEXR's ``envmap`` attribute
(``latlong`` → latlong, ``cube`` → cube-exr; OpenImageIO reports it as ``textureformat``
"LatLong Environment" or "CubeFace Environment"), then the aspect ratio. Aspects that only one
layout has are guessed: 3:4 cube-vcross, 4:3 cube-hcross, 6:1 cube-hstrip, 3:2 tennisball.
Shared aspects are refused with a message naming the candidates, except 2:1: a 2:1 image is a
lat-long unless it is black outside two inscribed disks, which is what an untagged packed
paraboloid looks like; then it is ambiguous too. 1:1 (sphere, angular, octahedral or
equal-area) and 1:6 (cube-vstrip or cube-exr) always need ``--from``. No pixel test tells the
square layouts apart: the two octahedral squares fill every pixel with the same kind of sky, and
pbrt-v4's ``imgtool makeequiarea`` writes no attribute that names its layout, so a pbrt file
is read with ``--from equal-area --in-convention pbrt``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import LayoutError
from .layouts import LAYOUTS, Layout, get_layout

__all__ = ["detect_layout"]

_UNIQUE_ASPECTS = {
    (3, 4): "cube-vcross",
    (4, 3): "cube-hcross",
    (6, 1): "cube-hstrip",
    (3, 2): "tennisball",
}
_SHARED_ASPECTS = {
    (1, 1): ("sphere", "angular", "octahedral", "equal-area"),
    (1, 6): ("cube-vstrip", "cube-exr"),
}


def detect_layout(
    width: int, height: int, metadata: dict[str, Any], pixels: np.ndarray | None = None
) -> tuple[Layout, int]:
    """Return (layout, guard) of an image, or raise LayoutError asking for ``--from``."""
    tag = metadata.get("envconv:layout")
    guard = int(metadata.get("envconv:guard", 0) or 0)
    if tag in LAYOUTS:
        layout = get_layout(tag)
        return layout, guard
    envmap = str(metadata.get("envmap", "")).lower()
    texture = str(metadata.get("textureformat", "")).lower()
    if envmap == "latlong" or texture == "latlong environment":
        return get_layout("latlong"), 0
    if envmap == "cube" or texture == "cubeface environment":
        return get_layout("cube-exr"), 0
    return _from_aspect(width, height, pixels), 0


def _from_aspect(width: int, height: int, pixels: np.ndarray | None) -> Layout:
    for (aw, ah), name in _UNIQUE_ASPECTS.items():
        if width * ah == height * aw:
            return get_layout(name)
    for (aw, ah), names in _SHARED_ASPECTS.items():
        if width * ah == height * aw:
            raise LayoutError(
                f"input is {width}x{height}: aspect {aw}:{ah} could be {_alternatives(names)} "
                "and the file has no layout metadata; pass --from"
            )
    if width == 2 * height:
        if pixels is not None and _black_outside_two_disks(pixels):
            raise LayoutError(
                f"input is {width}x{height} and black outside two disks: it could be latlong or "
                "paraboloid; pass --from"
            )
        return get_layout("latlong")
    raise LayoutError(f"input is {width}x{height}, which matches no layout's aspect; pass --from")


def _alternatives(names) -> str:
    return " or ".join(names) if len(names) < 3 else f"{', '.join(names[:-1])} or {names[-1]}"


def _black_outside_two_disks(pixels: np.ndarray) -> bool:
    height, width = pixels.shape[:2]
    n = height
    y = (np.arange(n) + 0.5) / n * 2 - 1
    x = (np.arange(width) + 0.5) / n
    x = np.where(x < 1.0, x * 2 - 1, (x - 1.0) * 2 - 1)
    outside = (x[None, :] ** 2 + y[:, None] ** 2) > 1.0 + 4.0 / n
    values = pixels[outside]
    return bool(values.size) and bool(np.all(values[..., : min(3, pixels.shape[2])] == 0))
