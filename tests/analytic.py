"""Analytic environments: radiance as a numpy function of direction.

World frame of docs/geometry.md: +Y up, +Z the lat-long centre, +X at u = 0.25. Every function
takes unit directions (..., 3) and returns radiance (..., 3), float64.

- :func:`radiance` is smooth, asymmetric in every axis (so a mirror or a swapped axis shows),
  different in each channel, and has two HDR highlights (peaks of about 40 and 8), wide enough
  to be resolved at the small sizes the tests use.
- :func:`smooth_radiance` is low-frequency with strong gradients and no highlight: errors near
  cell edges and in the interior are then comparable, which is what the seam tests need.
- :func:`sphere_mean` integrates any of them over the sphere (Gauss–Legendre in y, uniform in
  longitude), giving the exact solid-angle mean to ~1e-10.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "SUN",
    "radiance",
    "smooth_radiance",
    "lobe",
    "mirrored",
    "sphere_mean",
    "fibonacci_directions",
]

#: Direction of the main highlight: the docs/geometry.md test direction q.
SUN = np.array([0.48, 0.6, 0.64])
_MOON = np.array([-0.6, -0.3, -0.74]) / np.linalg.norm([-0.6, -0.3, -0.74])


def lobe(dirs, axis, sharpness):
    """exp(k (d·axis − 1)): 1 at ``axis``, falling to e^-1 about 1/√k radians away."""
    return np.exp(sharpness * (np.asarray(dirs, np.float64) @ np.asarray(axis) - 1.0))


def smooth_radiance(dirs) -> np.ndarray:
    """Low-frequency, gradient-rich, asymmetric radiance (values in about [0.2, 2.3])."""
    d = np.asarray(dirs, np.float64)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    r = 1.0 + 0.5 * np.sin(2.0 * x + 1.0) * np.cos(1.5 * y) + 0.3 * z + 0.2 * x * y
    g = 1.0 + 0.4 * np.cos(2.0 * z - 0.5) + 0.3 * y - 0.2 * x
    b = 1.2 + 0.6 * y + 0.3 * np.sin(1.7 * x - 2.0 * z) + 0.15 * x * z
    return np.stack([r, g, b], -1)


def radiance(dirs) -> np.ndarray:
    """Smooth asymmetric sky plus two coloured HDR highlights."""
    d = np.asarray(dirs, np.float64)
    sun = lobe(d, SUN / np.linalg.norm(SUN), 20.0)
    moon = lobe(d, _MOON, 12.0)
    colour_sun = np.array([40.0, 32.0, 24.0])
    colour_moon = np.array([3.0, 5.0, 8.0])
    return 0.5 * smooth_radiance(d) + sun[..., None] * colour_sun + moon[..., None] * colour_moon


def mirrored(fn, axis: int = 0):
    """``fn`` seen in a mirror that negates one world axis (0 = x)."""

    def flipped(dirs):
        d = np.array(dirs, np.float64, copy=True)
        d[..., axis] = -d[..., axis]
        return fn(d)

    return flipped


def sphere_mean(fn, n_lat: int = 256, n_lon: int = 512) -> np.ndarray:
    """Solid-angle mean (1/4π) ∫ fn(d) dΩ per channel; Gauss–Legendre in y = sin(lat)."""
    y, wy = np.polynomial.legendre.leggauss(n_lat)
    lon = (np.arange(n_lon) + 0.5) * (2 * math.pi / n_lon)
    rho = np.sqrt(1 - y * y)
    dirs = np.stack(
        [
            rho[:, None] * np.sin(lon)[None, :],
            np.broadcast_to(y[:, None], (n_lat, n_lon)),
            rho[:, None] * np.cos(lon)[None, :],
        ],
        -1,
    )
    values = np.asarray(fn(dirs), np.float64)
    # dΩ = dy dlon; Σ wy = 2 and Σ dlon = 2π, so the weights sum to 4π.
    weights = wy[:, None] * (2 * math.pi / n_lon)
    return np.einsum("ij,ijc->c", weights, values) / (4 * math.pi)


def fibonacci_directions(count: int) -> np.ndarray:
    """``count`` nearly uniform unit directions (count, 3) on the sphere."""
    k = np.arange(count) + 0.5
    y = 1 - 2 * k / count
    rho = np.sqrt(1 - y * y)
    phi = k * math.pi * (3 - math.sqrt(5))
    return np.stack([rho * np.cos(phi), y, rho * np.sin(phi)], -1)
