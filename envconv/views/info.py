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

from ..envmap import EnvMap
from ..errors import LayoutError
from ..layouts.geometry import pixel_solid_angles

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


def describe(path: str, layout: str | None = None, level: int = 0, part: str | None = None,
             stats: bool = False) -> dict[str, Any]:  # fmt: skip
    """A JSON-ready record of an image file (see the module docstring).

    The record comes from the file's headers alone (:func:`envconv.io.probe`): no pixel is
    read unless ``stats`` is true, which adds ``min``, ``max`` (per channel, finite values),
    ``nonfinite`` (count of NaN/Inf values) and ``mean_radiance`` (None for an image no
    layout fits), in the working space as :func:`envconv.io.read` gives the pixels.

    ``deep`` says whether the part described holds deep data; then ``samples_per_pixel`` is
    the [fewest, most] samples of a pixel (read from the deep data), the layout is ``unknown``
    (envconv reads no deep data as a map) and the ``stats`` values are None.

    ``size`` and ``guard`` are N and G of the level read (G >> level for a MIP level), None
    for an unknown layout; ``levels`` lists [width, height] of every MIP level's display
    window, level 0 first; windows are [x, y, width, height]. ``colorspace`` and
    ``metadata`` are the file's as stored (of the first file of a ``{face}`` set).

    A layout given as ``layout`` (``--from``) that the image does not fit raises LayoutError,
    as reading does; when detection finds none, ``layout`` is ``"unknown"``.
    """
    from ..color.ocio import input_colorspace_of
    from ..io import probe

    path = str(path)
    found = probe(path, layout, level, part)
    header = found.header
    record = {
        "path": path,
        "layout": found.layout.name if found.layout is not None else "unknown",
        "candidates": list(found.candidates),
        "reason": found.reason,
        "size": found.size,
        "guard": found.guard,
        "view": _view(found.layout),
        "width": found.width,
        "height": found.height,
        "display_window": list(header.display),
        "data_window": list(header.data),
        "level": level,
        "levels": [list(size) for size in found.levels],
        "channels": list(found.channels),
        "channel_types": _types(found.channels, header),
        "pixel_type": header.pixel_type,
        "deep": header.first.deep,
        "parts": _parts(header),
        "colorspace": input_colorspace_of(header.metadata, header.pixel_type),  # the file's
        "metadata": {k: (v if isinstance(v, (int, float, str)) else list(v))
                     for k, v in header.metadata.items()},
    }  # fmt: skip
    if header.first.deep:  # the only pixel data info reads without --stats: sample counts
        from ..io.files import deep_samples

        record["samples_per_pixel"] = list(deep_samples(path, header.chosen[0], level))
    if stats and header.first.deep:  # no image to take statistics of
        record.update(dict.fromkeys(("min", "max", "nonfinite", "mean_radiance")))
    elif stats:
        record.update(_stats(path, found, layout, level, part))
    return record


def _view(layout) -> dict[str, Any] | None:
    """An aimed layout's view (fov, yaw, pitch, roll in degrees), else None."""
    if layout is None or not layout.view:
        return None
    return {k: list(v) if isinstance(v, tuple) else v for k, v in layout.view_options.items()}


def _stats(path: str, found, layout: str | None, level: int, part: str | None) -> dict[str, Any]:
    """Range, non-finite count and mean radiance of the pixels, read in the working space."""
    from ..color.ocio import working_pixels
    from ..io import read, read_unplaced

    env = None
    if found.layout is not None:
        try:
            env = read(path, layout=layout, level=level, part=part)
        except LayoutError:  # a 2:1 image black outside two disks: latlong or paraboloid
            if layout is not None or "{face}" in path:
                raise
    if env is not None:
        pixels = env.pixels
    else:
        pixels, _ = read_unplaced(path, level, part)
        pixels = working_pixels(pixels, found.metadata, found.pixel_type)
    finite = np.isfinite(pixels)
    channels = range(pixels.shape[2])
    return {
        "min": [float(pixels[..., c][finite[..., c]].min(initial=np.inf)) for c in channels],
        "max": [float(pixels[..., c][finite[..., c]].max(initial=-np.inf)) for c in channels],
        "nonfinite": int((~finite).sum()),
        "mean_radiance": mean_radiance(env) if env is not None else None,
    }
