"""The layout registry: every layout by name.

Adding a layout means one new module and one line in ``_MODULE_LAYOUTS`` below (plus, for a new
geometry family, its code in ``src/core/chart.h``, its maps in ``src/core/layouts.h`` or
``src/core/views.h`` and one case in each dispatch in ``layouts.h``).
"""

from __future__ import annotations

import difflib

from ..errors import LayoutError
from ..lazy import package_getattr
from . import (
    angular,
    cube_exr,
    cube_faces,
    cube_hcross,
    cube_strip,
    cube_vcross,
    eac,
    equal_area,
    fisheye,
    latlong,
    octahedral,
    paraboloid,
    paraboloid_split,
    perspective,
    sphere,
    tennisball,
)
from .base import Cell, Layout

__all__ = [
    "LAYOUTS",
    "ALIASES",
    "FAMILIES",
    "Layout",
    "Cell",
    "get_layout",
    "layout_names",
    "resolve_layout_name",
]

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
    eac.LAYOUT,
    fisheye.LAYOUT,
    perspective.LAYOUT,
)

#: Every registered layout, by name, in documentation order.
LAYOUTS: dict[str, Layout] = {layout.name: layout for layout in _MODULE_LAYOUTS}


#: Other names for a layout, as other tools call it; accepted wherever a layout name is.
ALIASES: dict[str, str] = {"equirect": "latlong", "equirectangular": "latlong"}

#: Words that name a family of layouts rather than one: never taken, answered with the family.
#: "cubemap" has no single image layout in the tools envconv meets (cmft's ``cubemap`` is a
#: texture container, HDRShop's a cross, engines' six files), so the cube layouts are listed.
FAMILIES: dict[str, tuple[str, ...]] = dict.fromkeys(
    ("cubemap", "cube", "cube-map", "cubemaps"),
    ("cube-vcross", "cube-hcross", "cube-hstrip", "cube-vstrip", "cube-exr", "cube-faces"),
)


def layout_names() -> list[str]:
    """Names of all registered layouts, in documentation order."""
    return list(LAYOUTS)


def resolve_layout_name(name: str) -> str:
    """The registered name of layout ``name``: itself, or what an alias (:data:`ALIASES`)
    stands for, any case. LayoutError for a family word (``cubemap``: it lists the family)
    or an unknown name (with the close names, "did you mean", and the known ones)."""
    key = str(name).strip().lower()
    if key in LAYOUTS:
        return key
    if key in ALIASES:
        return ALIASES[key]
    if key in FAMILIES:
        raise LayoutError(
            f"{name!r} names several layouts; choose one of {', '.join(FAMILIES[key])}"
        )
    close = difflib.get_close_matches(key, [*LAYOUTS, *ALIASES], n=3)
    close = list(dict.fromkeys(ALIASES.get(c, c) for c in close))
    hint = "; did you mean " + " or ".join(f"'{c}'" for c in close) + "?" if close else ""
    raise LayoutError(f"unknown layout {name!r}{hint} (known: {', '.join(LAYOUTS)})")


def get_layout(name: str | Layout) -> Layout:
    """Return the layout called ``name`` (or an alias of it; a Layout passes through), or
    raise LayoutError (see :func:`resolve_layout_name`)."""
    if isinstance(name, Layout):
        return name
    return LAYOUTS[resolve_layout_name(name)]


# The geometry, rotation, conventions, face-set and detection modules load on first use.
__getattr__ = package_getattr(__name__)
