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
    """A JSON-ready record: layout, size, guard, dimensions, channels, range, mean, metadata."""
    from .io import read

    env = read(path, layout=layout, level=level)
    pixels = env.pixels
    finite = np.isfinite(pixels)
    record: dict[str, Any] = {
        "path": str(path),
        "layout": env.layout.name,
        "size": env.size,
        "guard": env.guard,
        "width": env.width,
        "height": env.height,
        "channels": list(env.channels),
        "pixel_type": env.pixel_type,
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
            k: (v if isinstance(v, (int, float, str)) else list(v)) for k, v in env.metadata.items()
        },
    }
    return record
