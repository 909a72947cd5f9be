"""Other tools' published square-sphere functions, re-expressed in numpy as test references.

Nothing here calls envconv. Each function restates, vectorised, what the cited source does, so
that tests can check envconv's octahedral layouts and presets against the tools themselves.

pbrt-v4 (github.com/mmp/pbrt-v4, Apache-2.0), read at commits 5359d2e3 of
``src/pbrt/util/math.cpp`` (revision 015ab470 computes the same with ApproxSin/ApproxCos),
00aad0a6 of ``src/pbrt/cmd/imgtool.cpp`` and 033e6d99 of ``src/pbrt/util/image.h``:

- ``EqualAreaSquareToSphere(p)``: Clarberg's mapping. p ∈ [0, 1]², (u, v) = 2p − 1; with the
  L1 distance s = 1 − (|u| + |v|) from the diagonal, r = 1 − |s|, φ = ((|v| − |u|)/r + 1) π/4
  (φ = π/4 at r = 0), z = ±(1 − r²) with the sign of s, and
  (x, y) = r √(2 − r²) (±cos φ, ±sin φ) with the signs of u and v.
- ``EqualAreaSphereToSquare(d)``: the inverse, with atan(b/a)·2/π (a = max(|x|, |y|),
  b = min) replaced by a 6th-degree polynomial; its error, measured here, is at most 4.1e-6
  (the constant term), so its (u, v) are within 2.1e-6 of the exact inverse.
- ``WrapEqualAreaSquare(uv)``: u < 0 → (−u, 1 − v); u > 1 → (2 − u, 1 − v); then
  v < 0 → (1 − u, −v); v > 1 → (1 − u, 2 − v).
- ``Image::Bilerp`` (``util/image.h``): x = u·W − 0.5, y = v·H − 0.5, bilinear between the four
  texels around (x, y); ``RemapPixelCoords`` wraps integer texels (Repeat: mod, Clamp: clamp,
  OctahedralSphere: x < 0 → (−x, H−1−y), x ≥ W → (2W−1−x, H−1−y), then the same in y).
- ``SphericalTheta(d) = acos(z)``, ``SphericalPhi(d) = atan2(y, x)`` mapped to [0, 2π).
- ``imgtool makeequiarea``: resolution defaults to the lat-long's width; every pixel (u, v),
  v counted from the top row, averages 6×6 stratified jittered filter samples of a Gaussian
  (radius 1.5 px, σ = 2) at p = WrapEqualAreaSquare((u + 0.5 + δx, v + 0.5 + δy)/N), reading
  the lat-long at (SphericalPhi/2π, SphericalTheta/π) with Repeat in u and Clamp in v; negative
  results are clamped to 0. :func:`make_equiarea` is deterministic: a regular S×S grid of
  offsets weighted by the filter instead of jittered samples weighted by filter/pdf.
- ``ImageInfiniteLight::ImageLe`` looks the square up at EqualAreaSphereToSquare(w) in the
  light's frame, with WrapMode::OctahedralSphere.

RTXGI-DDGI (github.com/NVIDIAGameWorks/RTXGI-DDGI, ``rtxgi-sdk/shaders/ddgi/include/
ProbeOctahedral.hlsl`` and ``ProbeBorderUpdateCS.hlsl``), the octahedral encoding of Cigolle et
al. 2014 as DDGI (Majercik et al. 2019) uses it:

- ``DDGIGetNormalizedOctahedralCoordinates``: texel (i, j) of an n×n probe → ((i + 0.5)/n,
  (j + 0.5)/n)·2 − 1, "the top left texel to (−1, −1)", so j counts rows from the top.
- ``DDGIGetOctahedralDirection(c)``: (c_x, c_y, 1 − |c_x| − |c_y|); where z < 0,
  (x, y) = (1 − |y|, 1 − |x|)·signNotZero(x, y); normalised. signNotZero(0) = +1.
- ``DDGIGetOctahedralCoordinates(d)``: (x, y)/(|x| + |y| + |z|), folded the same way for z < 0.
- Border update, probe side S = n + 2: border row texel (i, 0) copies (S − 1 − i, 1) and (i, S−1)
  copies (S − 1 − i, S − 2); columns likewise; corner (0, 0) copies (n, n), (S−1, 0) copies
  (1, n), (0, S−1) copies (n, 1), (S−1, S−1) copies (1, 1).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "equal_area_square_to_sphere",
    "equal_area_sphere_to_square",
    "wrap_equal_area_square",
    "remap_octahedral_texel",
    "spherical_theta",
    "spherical_phi",
    "bilerp",
    "make_equiarea",
    "image_le",
    "ddgi_normalized_coordinates",
    "ddgi_direction",
    "ddgi_coordinates",
    "ddgi_border_update",
]

# atan(x)·2/π on [0, 1], 6th-degree minimax (pbrt-v4 EqualAreaSphereToSquare).
_ATAN_POLY = (
    0.406758566246788489601959989e-5,
    0.636226545274016134946890922156,
    0.61572017898280213493197203466e-2,
    -0.247333733281268944196501420480,
    0.881770664775316294736387951347e-1,
    0.419038818029165735901852432784e-1,
    -0.251390972343483509333252996350e-1,
)


def _sign(value):
    """±1 with the sign bit of ``value`` (pbrt's copysign, so −0 counts as negative)."""
    return np.where(np.signbit(value), -1.0, 1.0)


def equal_area_square_to_sphere(p):
    """pbrt-v4 EqualAreaSquareToSphere of points (..., 2) in [0, 1]²; directions (..., 3)."""
    p = np.asarray(p, np.float64)
    u, v = 2 * p[..., 0] - 1, 2 * p[..., 1] - 1
    au, av = np.abs(u), np.abs(v)
    signed_distance = 1 - (au + av)
    r = 1 - np.abs(signed_distance)
    phi = np.where(r == 0, 1.0, (av - au) / np.where(r == 0, 1.0, r) + 1) * (math.pi / 4)
    z = _sign(signed_distance) * (1 - r * r)
    cos_phi = _sign(u) * np.abs(np.cos(phi))
    sin_phi = _sign(v) * np.abs(np.sin(phi))
    s = r * np.sqrt(np.maximum(2 - r * r, 0))
    return np.stack([cos_phi * s, sin_phi * s, z], -1)


def equal_area_sphere_to_square(d):
    """pbrt-v4 EqualAreaSphereToSquare of unit directions (..., 3); points (..., 2) in [0, 1]²."""
    d = np.asarray(d, np.float64)
    x, y, z = np.abs(d[..., 0]), np.abs(d[..., 1]), np.abs(d[..., 2])
    r = np.sqrt(np.maximum(1 - z, 0))
    a, b = np.maximum(x, y), np.minimum(x, y)
    b = np.where(a == 0, 0.0, b / np.where(a == 0, 1.0, a))
    phi = np.zeros_like(b)
    for coefficient in reversed(_ATAN_POLY):
        phi = phi * b + coefficient
    phi = np.where(x < y, 1 - phi, phi)
    v = phi * r
    u = r - v
    south = d[..., 2] < 0
    u, v = np.where(south, 1 - v, u), np.where(south, 1 - u, v)
    u = _sign(d[..., 0]) * u
    v = _sign(d[..., 1]) * v
    return np.stack([0.5 * (u + 1), 0.5 * (v + 1)], -1)


def wrap_equal_area_square(u, v):
    """pbrt-v4 WrapEqualAreaSquare of (u, v) in [−1, 2]² (float form)."""
    u = np.asarray(u, np.float64)
    v = np.asarray(v, np.float64)
    u, v = np.where(u < 0, -u, np.where(u > 1, 2 - u, u)), np.where((u < 0) | (u > 1), 1 - v, v)
    u, v = np.where((v < 0) | (v > 1), 1 - u, u), np.where(v < 0, -v, np.where(v > 1, 2 - v, v))
    return u, v


def remap_octahedral_texel(x, y, width, height):
    """pbrt-v4 RemapPixelCoords with WrapMode::OctahedralSphere (integer texels)."""
    x = np.asarray(x)
    y = np.asarray(y)
    x, y = (np.where(x < 0, -x, np.where(x >= width, 2 * width - 1 - x, x)),
            np.where((x < 0) | (x >= width), height - 1 - y, y))  # fmt: skip
    x, y = (np.where((y < 0) | (y >= height), width - 1 - x, x),
            np.where(y < 0, -y, np.where(y >= height, 2 * height - 1 - y, y)))  # fmt: skip
    return x, y


def spherical_theta(d):
    return np.arccos(np.clip(np.asarray(d)[..., 2], -1, 1))


def spherical_phi(d):
    d = np.asarray(d)
    phi = np.arctan2(d[..., 1], d[..., 0])
    return np.where(phi < 0, phi + 2 * math.pi, phi)


def _texels(image, x, y, wrap):
    height, width = image.shape[:2]
    if wrap == "octahedral":
        x, y = remap_octahedral_texel(x, y, width, height)
    else:  # lat-long: Repeat in x, Clamp in y
        x, y = np.mod(x, width), np.clip(y, 0, height - 1)
    return image[y, x]


def bilerp(image, u, v, wrap):
    """pbrt-v4 Image::Bilerp of ``image`` (H, W, C) at (u, v); wrap "latlong" or "octahedral"."""
    height, width = image.shape[:2]
    x = np.asarray(u) * width - 0.5
    y = np.asarray(v) * height - 0.5
    xi, yi = np.floor(x).astype(int), np.floor(y).astype(int)
    dx, dy = (x - xi)[..., None], (y - yi)[..., None]
    return (
        (1 - dx) * (1 - dy) * _texels(image, xi, yi, wrap)
        + dx * (1 - dy) * _texels(image, xi + 1, yi, wrap)
        + (1 - dx) * dy * _texels(image, xi, yi + 1, wrap)
        + dx * dy * _texels(image, xi + 1, yi + 1, wrap)
    )


def _gaussian(x, sigma):
    return np.exp(-x * x / (2 * sigma * sigma)) / math.sqrt(2 * math.pi * sigma * sigma)


def make_equiarea(latlong, resolution=None, samples=6, filter="gaussian"):
    """imgtool makeequiarea of a lat-long (H, W, C), deterministic (see the module docstring).

    ``filter="gaussian"`` is makeequiarea's GaussianFilter (radius 1.5, σ = 2): the filter value
    max(0, g(δ) − g(1.5)) per axis weights an S×S grid of offsets over [−1.5, 1.5]².
    ``filter="box"`` averages an S×S grid over the pixel itself.
    """
    latlong = np.asarray(latlong, np.float64)
    n = int(resolution or latlong.shape[1])
    if filter == "gaussian":
        offsets = (np.arange(samples) + 0.5) / samples * 3.0 - 1.5
        weights = np.maximum(_gaussian(offsets, 2.0) - _gaussian(1.5, 2.0), 0)
    else:
        offsets = (np.arange(samples) + 0.5) / samples - 0.5
        weights = np.ones(samples)
    centre = np.arange(n) + 0.5
    total = np.zeros((n, n, latlong.shape[2]))
    for oy, wy in zip(offsets, weights, strict=True):
        for ox, wx in zip(offsets, weights, strict=True):
            u, v = np.meshgrid((centre + ox) / n, (centre + oy) / n)
            u, v = wrap_equal_area_square(u, v)
            d = equal_area_square_to_sphere(np.stack([u, v], -1))
            values = bilerp(latlong, spherical_phi(d) / (2 * math.pi), spherical_theta(d) / math.pi,
                            "latlong")  # fmt: skip
            total += wx * wy * values
    return np.maximum(total / (weights.sum() ** 2), 0)


def image_le(square, w):
    """ImageInfiniteLight lookup of light-frame directions ``w`` (..., 3): nearest texel at
    EqualAreaSphereToSquare(w) with WrapMode::OctahedralSphere."""
    square = np.asarray(square)
    n = square.shape[0]
    p = equal_area_sphere_to_square(w)
    x = np.floor(p[..., 0] * n).astype(int)
    y = np.floor(p[..., 1] * n).astype(int)
    return _texels(square, x, y, "octahedral")


def ddgi_normalized_coordinates(i, j, n):
    """DDGIGetNormalizedOctahedralCoordinates of texel (i, j) of an n×n probe."""
    return (np.asarray(i) + 0.5) / n * 2 - 1, (np.asarray(j) + 0.5) / n * 2 - 1


def _sign_not_zero(value):
    return np.where(np.asarray(value) >= 0, 1.0, -1.0)


def ddgi_direction(cx, cy):
    """DDGIGetOctahedralDirection of normalized coordinates (c_x, c_y); unit vectors (..., 3)."""
    cx = np.asarray(cx, np.float64)
    cy = np.asarray(cy, np.float64)
    z = 1 - np.abs(cx) - np.abs(cy)
    fx = (1 - np.abs(cy)) * _sign_not_zero(cx)
    fy = (1 - np.abs(cx)) * _sign_not_zero(cy)
    x, y = np.where(z < 0, fx, cx), np.where(z < 0, fy, cy)
    d = np.stack([x, y, z], -1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def ddgi_coordinates(d):
    """DDGIGetOctahedralCoordinates of directions (..., 3): (c_x, c_y) in [−1, 1]²."""
    d = np.asarray(d, np.float64)
    l1 = np.abs(d).sum(-1)
    cx, cy = d[..., 0] / l1, d[..., 1] / l1
    fx = (1 - np.abs(cy)) * _sign_not_zero(cx)
    fy = (1 - np.abs(cx)) * _sign_not_zero(cy)
    south = d[..., 2] < 0
    return np.where(south, fx, cx), np.where(south, fy, cy)


def ddgi_border_update(probe):
    """Fill the 1-texel border of one probe (S × S × C, S = n + 2) as ProbeBorderUpdateCS does."""
    out = np.array(probe, copy=True)
    s = out.shape[0]
    n = s - 2
    inner = np.arange(1, s - 1)
    out[0, inner] = out[1, s - 1 - inner]
    out[s - 1, inner] = out[s - 2, s - 1 - inner]
    out[inner, 0] = out[s - 1 - inner, 1]
    out[inner, s - 1] = out[s - 1 - inner, s - 2]
    out[0, 0], out[0, s - 1] = out[n, n], out[n, 1]
    out[s - 1, 0], out[s - 1, s - 1] = out[1, n], out[1, 1]
    return out
