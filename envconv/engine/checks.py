"""What the walker (:mod:`envconv.engine.walk`) checks before any pixel is read: colour-space
names, conventions and MIP chains the output paths cannot hold. Both are bad usage (UsageError, exit 2),
refused in the walker's check mode, so that a chain, ``convert``, a graph file and a batch
refuse them before any work, whatever reads the steps.
"""

from __future__ import annotations

from typing import Any

from .. import io
from ..errors import LayoutError, UsageError
from ..layouts import get_layout
from .steps import count_levels

__all__ = ["check_colorspace_name", "check_levels", "check_conventions", "working_space"]


def working_space() -> dict[str, str]:
    """The metadata of a map as the engine holds it: pixels in the working space."""
    from ..color.ocio import WORKING_COLORSPACE

    return {"oiio:ColorSpace": WORKING_COLORSPACE}


def check_colorspace_name(name: str | None, config: str | None) -> None:
    """Refuse a colour space the OCIO config does not know (:func:`envconv.color.ocio.check_colorspace`)."""
    if name:
        from ..color.ocio import check_colorspace

        check_colorspace(name, config)


def check_levels(layout: str, template: str, request: dict[str, Any]) -> None:
    """Refuse, before any header is read, a MIP chain the output path cannot hold (the
    writer's rule, :func:`envconv.io.write_plan.check_write`). ``request`` holds the
    resample's keywords; the full chain's length is known only when they name the size."""
    from ..resample.options import check_mips

    levels = check_mips(request.get("mips"))[0]
    if levels is None:
        return
    guard = request.get("guard", 0)
    guard = 0 if guard == "fill" else int(guard)
    size, full, count = request.get("size"), None, levels
    if size:
        width, height = get_layout(layout).file_size(int(size), guard)
        full = count_levels(width, height, True)
        count = count_levels(width, height, request.get("mips"))
    io.check_write(layout, template, count, full, guard)


def check_conventions(kwargs: dict[str, Any], source_layout=None) -> None:
    """Refuse, as bad usage, a resample's conventions that do not fit its layouts (the
    output's from the arguments; the input's once ``source_layout`` is known from the
    header), with the rule of :func:`envconv.resample.options.check_conventions`, and
    ``--up z`` with ``--axes``."""
    from ..layouts.conventions import environment_axes
    from ..resample.options import check_conventions as check

    environment_axes(kwargs.get("up"), kwargs.get("axes"))  # --up z with --axes
    try:
        check(kwargs["to"], kwargs.get("out_convention"), kwargs.get("mips"), source_layout,
              kwargs.get("in_convention"), kwargs.get("guard", 0))  # fmt: skip
    except LayoutError as exc:  # a convention named for another layout: the user's arguments
        raise UsageError(str(exc)) from None
