"""A lat-long's sample grid on the way into and out of :func:`envconv.convert`.

Resampling works on envconv's pixel centres. A source stored on another grid (the input
convention's, e.g. ``mitsuba``, or else the grid its ``envconv:grid`` tag records) is first
resampled onto the centres, and an output for a tool with another grid is resampled onto that
grid last and tagged with it; see :mod:`envconv.layouts.grids`.
"""

from __future__ import annotations

from dataclasses import replace

from ..envmap import EnvMap
from ..errors import UsageError
from ..layouts.conventions import Convention
from ..layouts.grids import CENTRES, GRID_TAG, from_centres, tagged_grid, to_centres

__all__ = ["source_on_centres", "check_output_grid", "output_on_grid"]


def source_on_centres(envmap: EnvMap, convention: Convention | None) -> EnvMap:
    """``envmap`` on envconv's pixel centres, untagged.

    ``convention`` is the resolved input convention when one was given: its grid wins over the
    map's own tag (None: the tag says).
    """
    grid = tagged_grid(envmap.metadata) if convention is None else convention.grid
    metadata = {k: v for k, v in envmap.metadata.items() if k != GRID_TAG}
    if grid == CENTRES:
        return envmap if GRID_TAG not in envmap.metadata else replace(envmap, metadata=metadata)
    if envmap.layout.name != "latlong" or envmap.guard:
        raise UsageError(f"a {grid} grid applies to a lat-long without a guard ring, "
                         f"not {envmap.layout.name} with guard {envmap.guard}")  # fmt: skip
    return replace(envmap, pixels=to_centres(envmap.pixels, grid), metadata=metadata, levels=None)


def check_output_grid(convention: Convention, mips, guard) -> None:
    """Refuse what an output on another grid cannot carry: MIP levels and guard rings."""
    if convention.grid == CENTRES:
        return
    if mips:
        raise UsageError(f"out_convention {convention.name} puts samples on a {convention.grid} "
                         "grid; it cannot be used with mips")  # fmt: skip
    if guard:
        raise UsageError(f"out_convention {convention.name} puts samples on a {convention.grid} "
                         "grid; it cannot be used with a guard ring")  # fmt: skip


def output_on_grid(pixels, convention: Convention, metadata: dict) -> tuple:
    """(pixels, metadata) of an output resampled onto ``convention``'s grid and tagged with it
    (unchanged, and untagged, on envconv's centres)."""
    metadata = {k: v for k, v in metadata.items() if k != GRID_TAG}
    if convention.grid == CENTRES:
        return pixels, metadata
    metadata[GRID_TAG] = convention.grid
    return from_centres(pixels, convention.grid), metadata
