"""Facts about an image file, for ``envconv info``: any image, environment map or not.

:func:`describe` always reports the file's size, display and data windows, channels and their
types, parts, colour space, value range and metadata. When the image is a map it also gives
the layout, N, guard and mean radiance; when it cannot be placed in a layout, ``layout`` is
``"unknown"`` and ``candidates`` and ``reason`` say which layouts were weighed and why none
was chosen.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .envmap import EnvMap
from .errors import LayoutError
from .geometry import pixel_solid_angles

__all__ = ["describe", "mean_radiance"]


def mean_radiance(envmap: EnvMap) -> list[float]:
    """Solid-angle-weighted mean of every channel over the valid region (per steradian)."""
    omega = pixel_solid_angles(envmap.layout, envmap.size, envmap.guard, samples=4)
    total = omega.sum()
    weighted = np.einsum("hw,hwc->c", omega, np.nan_to_num(envmap.pixels.astype(np.float64)))
    return [float(v) for v in weighted / total]


def _parts(header) -> list[dict[str, Any]]:
    skipped = dict(header.skipped)
    records = []
    for index, part in enumerate(header.parts):
        name = part.name if part is not None else ""
        record: dict[str, Any] = {"index": index, "name": name, "read": index in header.chosen}
        if part is not None:
            record.update(channels=list(part.channels), channel_types=list(part.channel_types),
                          display_window=list(part.display), data_window=list(part.data),
                          deep=part.deep)  # fmt: skip
        if not record["read"]:
            record["why"] = skipped.get(name or str(index), "no such MIP level")
        records.append(record)
    return records


def _types(channels, header) -> list[str | None]:
    """The stored type of each channel, None for an ``A`` the file does not hold."""
    stored = dict(zip(header.channels, header.channel_types, strict=True))
    return [stored.get(name) for name in channels]


def describe(path: str, layout: str | None = None, level: int = 0, part: str | None = None) -> dict[str, Any]:
    """A JSON-ready record of an image file (see the module docstring).

    ``size`` and ``guard`` are N and G of the level read (G >> level for a MIP level), None
    for an unknown layout; ``levels`` lists [width, height] of every MIP level's display
    window, level 0 first; windows are [x, y, width, height]. Values (``min``, ``max``,
    ``mean_radiance``) are in the working space, as :func:`envconv.io.read` gives them.

    A layout given as ``layout`` (``--from``) that the image does not fit raises LayoutError,
    as reading does; when detection finds none, ``layout`` is ``"unknown"``.
    """
    from .color import input_colorspace_of, working_pixels
    from .detect import find_layout
    from .io import mip_levels, read, read_unplaced
    from .io.face_files import first_file
    from .io.files import read_file_header

    path = str(path)
    header = read_file_header(first_file(path, layout), level, part)
    try:
        env = read(path, layout=layout, level=level, part=part)
    except LayoutError:
        if layout is not None or "{face}" in path:
            raise
        env = None
    if env is None:
        pixels, channels = read_unplaced(path, level, part)
        pixels = working_pixels(pixels, header.metadata, header.pixel_type)
    else:
        pixels, channels = env.pixels, env.channels
    if layout is not None:
        candidates, reason = (layout,), "given by --from"
    elif "{face}" in path:
        candidates, reason = (env.layout.name,), "{face} in the path: one file per face"
    else:
        candidates, reason = find_layout(header.width, header.height, header.metadata, pixels)[2:]
    finite = np.isfinite(pixels)
    metadata = header.metadata if "{face}" not in path else env.metadata
    return {
        "path": path,
        "layout": env.layout.name if env is not None else "unknown",
        "candidates": list(candidates),
        "reason": reason,
        "size": env.size if env is not None else None,
        "guard": env.guard if env is not None else None,
        "width": int(pixels.shape[1]),
        "height": int(pixels.shape[0]),
        "display_window": list(header.display),
        "data_window": list(header.data),
        "level": level,
        "levels": [list(size) for size in mip_levels(path, part)],
        "channels": list(channels),
        "channel_types": _types(channels, header),
        "pixel_type": header.pixel_type,
        "parts": _parts(header),
        "colorspace": input_colorspace_of(header.metadata, header.pixel_type),  # the file's
        "min": [float(pixels[..., c][finite[..., c]].min(initial=np.inf)) for c in range(pixels.shape[2])],
        "max": [float(pixels[..., c][finite[..., c]].max(initial=-np.inf)) for c in range(pixels.shape[2])],
        "nonfinite": int((~finite).sum()),
        "mean_radiance": mean_radiance(env) if env is not None else None,
        "metadata": {k: (v if isinstance(v, (int, float, str)) else list(v)) for k, v in metadata.items()},
    }  # fmt: skip
