"""Facts about an environment map file, for ``envconv info``."""

from __future__ import annotations

from typing import Any

import numpy as np

from .envmap import EnvMap
from .geometry import pixel_solid_angles

__all__ = ["describe", "mean_radiance"]


def mean_radiance(envmap: EnvMap) -> list[float]:
    """Solid-angle-weighted mean of every channel over the valid region (per steradian)."""
    omega = pixel_solid_angles(envmap.layout, envmap.size, envmap.guard, samples=4)
    total = omega.sum()
    weighted = np.einsum("hw,hwc->c", omega, np.nan_to_num(envmap.pixels.astype(np.float64)))
    return [float(v) for v in weighted / total]


def describe(path: str, layout: str | None = None, level: int = 0) -> dict[str, Any]:
    """A JSON-ready record: layout, size, guard, dimensions, MIP levels, channels, range, mean.

    ``size`` and ``guard`` are N and G of the level read (G >> level for a MIP level);
    ``levels`` lists [width, height] of every MIP level in the file, level 0 first.
    """
    from .colorflow import input_colorspace_of
    from .io import mip_levels, read, read_header

    env = read(path, layout=layout, level=level)
    # Every header attribute (envconv:*, compression, chromaticities...), not only content.
    header = read_header(path, level)[3] if "{face}" not in str(path) else env.metadata
    colorspace = input_colorspace_of(header, env.pixel_type)  # the file's, as read
    pixels = env.pixels
    finite = np.isfinite(pixels)
    record: dict[str, Any] = {
        "path": str(path),
        "layout": env.layout.name,
        "size": env.size,
        "guard": env.guard,
        "width": env.width,
        "height": env.height,
        "level": level,
        "levels": [list(size) for size in mip_levels(path)],
        "channels": list(env.channels),
        "pixel_type": env.pixel_type,
        "colorspace": colorspace,
        "min": [
            float(pixels[..., c][finite[..., c]].min(initial=np.inf))
            for c in range(pixels.shape[2])
        ],
        "max": [
            float(pixels[..., c][finite[..., c]].max(initial=-np.inf))
            for c in range(pixels.shape[2])
        ],
        "nonfinite": int((~finite).sum()),
        "mean_radiance": mean_radiance(env),
        "metadata": {
            k: (v if isinstance(v, (int, float, str)) else list(v)) for k, v in header.items()
        },
    }
    return record
