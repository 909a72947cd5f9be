"""The layout registry: every layout by name.

Adding a layout means one new module and one line in ``_MODULE_LAYOUTS`` below (plus, for a new
geometry family, its maps in ``src/core/layouts.h`` and one case in each dispatch there).
"""

from __future__ import annotations

import difflib

from ..errors import LayoutError
from . import (
    angular,
    cube_exr,
    cube_faces,
    cube_hcross,
    cube_strip,
    cube_vcross,
    equal_area,
    latlong,
    octahedral,
    paraboloid,
    paraboloid_split,
    sphere,
    tennisball,
)
from .base import Cell, Layout

__all__ = ["LAYOUTS", "Layout", "Cell", "get_layout", "layout_names"]

_MODULE_LAYOUTS = (
    latlong.LAYOUT,
    cube_vcross.LAYOUT,
    cube_hcross.LAYOUT,
    cube_strip.HSTRIP,
    cube_strip.VSTRIP,
    cube_exr.LAYOUT,
    cube_faces.LAYOUT,
    sphere.LAYOUT,
    angular.LAYOUT,
    paraboloid.LAYOUT,
    paraboloid_split.LAYOUT,
    tennisball.LAYOUT,
    octahedral.LAYOUT,
    equal_area.LAYOUT,
)

#: Every registered layout, by name, in documentation order.
LAYOUTS: dict[str, Layout] = {layout.name: layout for layout in _MODULE_LAYOUTS}


def layout_names() -> list[str]:
    """Names of all registered layouts, in documentation order."""
    return list(LAYOUTS)


def get_layout(name: str | Layout) -> Layout:
    """Return the layout called ``name`` (a Layout passes through), or raise LayoutError."""
    if isinstance(name, Layout):
        return name
    try:
        return LAYOUTS[name]
    except KeyError:
        close = difflib.get_close_matches(str(name), LAYOUTS, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise LayoutError(f"unknown layout {name!r}{hint} (known: {', '.join(LAYOUTS)})") from None
