"""A slow, obviously correct numpy reference for envconv's geometry and resampler.

Everything here is written out again from ``docs/geometry.md`` and deliberately calls
no envconv function, so that tests comparing envconv with this module compare two independent
readings of the contract.

Coordinates: (u, v) in [0, 1]² of the whole image (u right, v down), pixel (i, j) of a W×H image
centred at ((i + 0.5)/W, (j + 0.5)/H). Multi-file layouts (cube-faces, paraboloid-split) are
described by their in-memory mosaic: the cells side by side in face order. Within a cell, local
(a, b) ∈ [-1, 1]² run a right and b down; disk formulas use (X, Y) = (a, -b).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "GRIDS",
    "image_size",
    "face_to_dir",
    "face_density",
    "fold_square",
    "uv_to_dir",
    "subsample_uv",
    "sample_latlong",
    "naive_convert",
    "pixel_average",
    "pixel_solid_angles",
]

# Cell tables copied from docs/geometry.md: family, columns, rows, cell aspect (width in N),
# and (col, row, face, rotated 180°) for every occupied cell. Cube GL face order is
# +X_c, −X_c, +Y_c, −Y_c, +Z_c, −Z_c; cube-exr order is +X, −X, +Y, −Y, +Z, −Z.
_STRIP_H = tuple((k, 0, k, False) for k in range(6))
_STRIP_V = tuple((0, k, k, False) for k in range(6))
GRIDS = {
    "latlong": ("latlong", 1, 1, 2, ((0, 0, 0, False),)),
    "cube-vcross": (
        "cube",
        3,
        4,
        1,
        (
            (1, 0, 2, False),
            (0, 1, 1, False),
            (1, 1, 4, False),
            (2, 1, 0, False),
            (1, 2, 3, False),
            (1, 3, 5, True),
        ),
    ),  # fmt: skip
    "cube-hcross": (
        "cube",
        4,
        3,
        1,
        (
            (1, 0, 2, False),
            (0, 1, 1, False),
            (1, 1, 4, False),
            (2, 1, 0, False),
            (3, 1, 5, False),
            (1, 2, 3, False),
        ),
    ),  # fmt: skip
    "cube-hstrip": ("cube", 6, 1, 1, _STRIP_H),
    "cube-vstrip": ("cube", 1, 6, 1, _STRIP_V),
    "cube-faces": ("cube", 6, 1, 1, _STRIP_H),
    "cube-exr": ("cube-exr", 1, 6, 1, _STRIP_V),
    "sphere": ("sphere", 1, 1, 1, ((0, 0, 0, False),)),
    "angular": ("angular", 1, 1, 1, ((0, 0, 0, False),)),
    "paraboloid": ("paraboloid", 2, 1, 1, ((0, 0, 0, False), (1, 0, 1, False))),
    "paraboloid-split": ("paraboloid", 2, 1, 1, ((0, 0, 0, False), (1, 0, 1, False))),
    "tennisball": ("tennisball", 1, 2, 3, ((0, 0, 0, False), (0, 1, 1, False))),
    "octahedral": ("octahedral", 1, 1, 1, ((0, 0, 0, False),)),
    "equal-area": ("equal-area", 1, 1, 1, ((0, 0, 0, False),)),
    # ffmpeg v360 eac: faces in a 3 x 2 grid, each in its own cell, turned by its own formula.
    "eac": ("eac", 3, 2, 1, tuple((k % 3, k // 3, k, False) for k in range(6))),
    # The registry's default views: fisheye fov 180, perspective fov 90 x 90, both at +Z.
    "fisheye": ("fisheye", 1, 1, 1, ((0, 0, 0, False),)),
    "perspective": ("perspective", 1, 1, 1, ((0, 0, 0, False),)),
}
DISK_FAMILIES = ("sphere", "angular", "paraboloid", "fisheye")
#: Layouts that cover part of the sphere with their default view, and the test of what they see.
PARTIAL = {
    "fisheye": lambda d: np.asarray(d)[..., 2] > 0,  # fov 180: the front hemisphere
    "perspective": lambda d: np.all(  # fov 90 x 90: |x|, |y| < z
        np.abs(np.asarray(d)[..., :2]) < np.asarray(d)[..., 2:], axis=-1
    ),
}
OCTAHEDRAL_FAMILIES = ("octahedral", "equal-area")


def image_size(name: str, n: int) -> tuple[int, int]:
    """(W, H) of layout ``name`` at size N (the mosaic for multi-file layouts)."""
    _, cols, rows, aspect, _ = GRIDS[name]
    return cols * aspect * n, rows * n


def _normalise(x, y, z):
    norm = np.sqrt(x * x + y * y + z * z)
    return np.stack([x / norm, y / norm, z / norm], -1)


def _cube_gl(face, a, b):
    """The GL/D3D/KTX table in the cube frame c, then d = normalise(−c_x, c_y, c_z)."""
    one = np.ones_like(a)
    table = [
        (one, -b, -a),  # +X_c
        (-one, -b, a),  # -X_c
        (a, one, b),  # +Y_c
        (a, -one, -b),  # -Y_c
        (a, -b, one),  # +Z_c
        (-a, -b, -one),  # -Z_c
    ]
    cx, cy, cz = (np.choose(face, [t[k] for t in table]) for k in range(3))
    return _normalise(-cx, cy, cz)


def _cube_exr(face, a, b):
    one = np.ones_like(a)
    table = [
        (one, -b, a),  # +X
        (-one, -b, -a),  # -X
        (a, one, -b),  # +Y
        (a, -one, b),  # -Y
        (-a, -b, one),  # +Z
        (a, -b, -one),  # -Z
    ]
    x, y, z = (np.choose(face, [t[k] for t in table]) for k in range(3))
    return _normalise(x, y, z)


def fold_square(a, b):
    """The octahedral fold: a point past the square's edge is the point mirrored across that edge
    and across the edge's midpoint, (a, b) → (±2 − a, −b) or (−a, ±2 − b), until inside.

    Written from the rule that both edge halves show the same directions (an edge point (1, b)
    and (1, −b) are one direction); pbrt-v4's WrapEqualAreaSquare states the same rule in (u, v).
    """
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    for _ in range(4):
        a, b = (np.where(a > 1, 2 - a, np.where(a < -1, -2 - a, a)),
                np.where((a > 1) | (a < -1), -b, b))  # fmt: skip
        a, b = (np.where((b > 1) | (b < -1), -a, a),
                np.where(b > 1, 2 - b, np.where(b < -1, -2 - b, b)))  # fmt: skip
    return a, b


def _octahedron_point(a, b):
    """Point (c_x, c_y, c_z) of the octahedron |x| + |y| + |z| = 1 over square point (a, b), with
    the lower half (c_z < 0) unfolded from the square's corners (Cigolle et al. 2014)."""
    upper = np.abs(a) + np.abs(b) <= 1
    sa = np.where(a >= 0, 1.0, -1.0)
    sb = np.where(b >= 0, 1.0, -1.0)
    cx = np.where(upper, a, sa * (1 - np.abs(b)))
    cy = np.where(upper, b, sb * (1 - np.abs(a)))
    return cx, cy, 1 - np.abs(a) - np.abs(b)


def _octahedral_family(family, a, b):
    """Directions of the two octahedral squares, in the z-up frame of the papers, then turned
    into envconv's: the papers' +Z (the square's centre) is +Y, their +X (right) is +X and their
    +Y (down) is −Z, i.e. d = (t_x, t_z, −t_y)."""
    a, b = fold_square(a, b)
    cx, cy, cz = _octahedron_point(a, b)
    if family == "octahedral":
        t = _normalise(cx, cy, cz)
    else:
        # Clarberg 2008: the L1 radius r of the point on the diamond fixes the polar angle
        # (z = 1 − r², equal-area), and its position along the diamond's edge the azimuth.
        r = np.abs(cx) + np.abs(cy)
        along = np.abs(cy) / np.where(r > 0, r, 1.0)
        psi = 0.5 * math.pi * along
        sin_theta = r * np.sqrt(2 - r * r)
        tz = np.where(cz >= 0, 1.0, -1.0) * (1 - r * r)
        sx = np.where(cx >= 0, 1.0, -1.0)
        sy = np.where(cy >= 0, 1.0, -1.0)
        t = np.stack([sx * np.cos(psi) * sin_theta, sy * np.sin(psi) * sin_theta, tz], -1)
    return np.stack([t[..., 0], t[..., 2], -t[..., 1]], -1)


def _from_ffmpeg(x, y, z):
    """ffmpeg v360's frame (x right, y down, z front; its "front" the lat-long's centre, its
    right the lat-long's right of it) in envconv's: (−x, −y, z)."""
    return _normalise(-x, -y, z)


def _eac_plane(e):
    """The cube-plane coordinate of an equi-angular one: tan(π/4 · e) on the face; past its
    edge (a guard ring) the plane goes on at the edge's rate, 1 + π/2 (|e| − 1) (ffmpeg's own
    padding goes on at rate 1 instead; envconv's docs/conventions.md states this rule)."""
    e = np.asarray(e, np.float64)
    past = np.sign(e) * (1 + 0.5 * math.pi * (np.abs(e) - 1))
    return np.where(np.abs(e) <= 1, np.tan(0.25 * math.pi * np.clip(e, -1, 1)), past)


def _eac(face, ea, eb):
    """ffmpeg 5.1 vf_v360.c ``eac_to_xyz`` without its padding: uf, vf = tan(π/2 · e/2), then
    the six cells' vectors as the switch writes them (TOP_LEFT … BOTTOM_RIGHT)."""
    uf = _eac_plane(ea)
    vf = _eac_plane(eb)
    one = np.ones_like(uf)
    table = [
        (-one, vf, uf),  # TOP_LEFT
        (uf, vf, one),  # TOP_MIDDLE
        (one, vf, -uf),  # TOP_RIGHT
        (-vf, one, -uf),  # BOTTOM_LEFT
        (-vf, -uf, -one),  # BOTTOM_MIDDLE
        (-vf, -one, uf),  # BOTTOM_RIGHT
    ]
    x, y, z = (np.choose(face, [t[k] for t in table]) for k in range(3))
    return _from_ffmpeg(x, y, z)


def fisheye_dir(a, b, fov=180.0):
    """ffmpeg 5.1 ``fisheye_to_xyz`` with h_fov = v_fov = ``fov`` at image point (a, b):
    uf, vf = (fov/180)(a, b), φ = atan2(vf, uf), θ = π/2 (1 − |(uf, vf)|),
    vec = (cos θ cos φ, cos θ sin φ, sin θ)."""
    uf, vf = fov / 180.0 * a, fov / 180.0 * b
    phi = np.arctan2(vf, uf)
    theta = 0.5 * math.pi * (1 - np.hypot(uf, vf))
    return _from_ffmpeg(np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi), np.sin(theta))


def perspective_dir(a, b, fov_h=90.0, fov_v=90.0):
    """py360convert ``xyzpers`` at u_deg = v_deg = 0 at image point (a, b): (x, −y, 1) with
    x = a tan(fov_h/2), y = b tan(fov_v/2), in its frame (x right, y up, z the lat-long's
    centre, +x at u = 0.75 of its lat-long), which is envconv's with x negated."""
    x = a * math.tan(math.radians(fov_h) / 2)
    y = b * math.tan(math.radians(fov_v) / 2)
    return _normalise(-x, -y, np.ones_like(x))


def face_to_dir(family: str, face, a, b) -> np.ndarray:
    """Unit direction (..., 3) of local point (a, b) of ``face`` (inside the valid region)."""
    face = np.asarray(face)
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    if family == "latlong":
        lon = 2 * math.pi * (0.5 - (a + 1) / 2)
        lat = math.pi * (0.5 - (b + 1) / 2)
        return np.stack([np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)], -1)
    if family == "cube":
        return _cube_gl(face, a, b)
    if family == "cube-exr":
        return _cube_exr(face, a, b)
    X, Y = a, -b
    r2 = X * X + Y * Y
    if family == "sphere":
        nz = np.sqrt(np.clip(1 - r2, 0, None))
        return np.stack([2 * nz * X, 2 * nz * Y, 2 * nz * nz - 1], -1)
    if family == "angular":
        r = np.sqrt(r2)
        alpha = math.pi * r
        safe = np.where(r > 0, r, 1.0)
        s = np.where(r > 0, np.sin(alpha) / safe, 0.0)
        return np.stack([s * X, s * Y, np.cos(alpha)], -1)
    if family == "paraboloid":
        s = 1 + r2
        z = np.where(face == 0, 1 - r2, -(1 - r2))
        return np.stack([2 * X / s, 2 * Y / s, z / s], -1)
    if family in OCTAHEDRAL_FAMILIES:
        return _octahedral_family(family, a, b)
    if family == "tennisball":
        phi = (0.5 - (a + 1) / 2) * (1.5 * math.pi)
        theta = (0.5 - (b + 1) / 2) * (0.5 * math.pi)
        c1 = np.stack([np.sin(phi) * np.cos(theta), np.sin(theta), np.cos(phi) * np.cos(theta)], -1)
        c2 = np.stack(
            [np.sin(theta), np.sin(phi) * np.cos(theta), -np.cos(phi) * np.cos(theta)], -1
        )
        return np.where((face == 0)[..., None], c1, c2)
    if family == "eac":
        return _eac(face, a, b)
    if family == "fisheye":
        return fisheye_dir(a, b)
    if family == "perspective":
        return perspective_dir(a, b)
    raise ValueError(family)


def face_density(family: str, face, a, b) -> np.ndarray:
    """Solid angle per unit (a, b) area (sr), derived by hand for each family."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    r2 = a * a + b * b
    if family == "latlong":  # dΩ = cos(lat) dlon dlat, dlon = π da, dlat = π/2 db
        return np.abs(np.cos(0.5 * math.pi * b)) * (0.5 * math.pi * math.pi)
    if family in ("cube", "cube-exr"):  # gnomonic
        return (1 + r2) ** -1.5
    if family == "sphere":  # α = 2 asin R: sin α dα / (R dR) = 4
        return np.full_like(r2, 4.0)
    if family == "angular":  # α = πR: π sin(πR) / R
        r = np.sqrt(r2)
        return np.where(
            r > 1e-12, math.pi * np.sin(math.pi * r) / np.where(r > 0, r, 1), math.pi**2
        )
    if family == "paraboloid":
        return 4.0 / (1 + r2) ** 2
    if family == "equal-area":  # 4π over the area-4 square, everywhere
        return np.full_like(r2, math.pi)
    if family == "octahedral":  # a plane patch at distance |c| seen at cos = 1/(√3 |c|)
        cx, cy, cz = _octahedron_point(*fold_square(a, b))
        return (cx * cx + cy * cy + cz * cz) ** -1.5
    if family == "tennisball":  # dΩ = cos θ dφ dθ, dφ = 3π/4 da, dθ = π/4 db
        return np.abs(np.cos(0.25 * math.pi * b)) * (0.75 * math.pi * 0.25 * math.pi)
    if family == "eac":  # gnomonic at (tan πa/4, tan πb/4), times d tan(πe/4)/de twice
        ta, tb = np.tan(0.25 * math.pi * a), np.tan(0.25 * math.pi * b)
        rate = (0.25 * math.pi) ** 2 * (1 + ta * ta) * (1 + tb * tb)
        return rate * (1 + ta * ta + tb * tb) ** -1.5
    if family == "fisheye":  # θ = (π/2) R: (π/2) sin((π/2) R) / R
        r = np.sqrt(r2)
        h = 0.5 * math.pi
        return np.where(r > 1e-12, h * np.sin(h * r) / np.where(r > 0, r, 1), h * h)
    if family == "perspective":  # tan 45° = 1: the plane at distance 1
        return (1 + r2) ** -1.5
    raise ValueError(family)


def _locate(name: str, u, v):
    """(face, a, b, occupied) of image points; face is 0 where the cell is empty."""
    _, cols, rows, _, cells = GRIDS[name]
    u = np.asarray(u, np.float64)
    v = np.asarray(v, np.float64)
    col = np.clip(np.floor(u * cols), 0, cols - 1).astype(int)
    row = np.clip(np.floor(v * rows), 0, rows - 1).astype(int)
    a = 2 * (u * cols - col) - 1
    b = 2 * (v * rows - row) - 1
    face = np.zeros(u.shape, int)
    occupied = np.zeros(u.shape, bool)
    for c, r, f, rotated in cells:
        here = (col == c) & (row == r)
        face[here] = f
        occupied |= here
        if rotated:
            a = np.where(here, -a, a)
            b = np.where(here, -b, b)
    return face, a, b, occupied


def uv_to_dir(name: str, u, v):
    """Directions (..., 3), validity (...) and density per unit (a, b) area of image points."""
    family = GRIDS[name][0]
    face, a, b, valid = _locate(name, u, v)
    if family in DISK_FAMILIES:
        valid &= a * a + b * b <= 1.0
    dirs = face_to_dir(family, face, a, b)
    dirs = np.where(valid[..., None], dirs, 0.0)
    return dirs, valid, face_density(family, face, a, b)


def subsample_uv(name: str, n: int, samples: int, offset=(0.0, 0.0), window=None):
    """(u, v) of S×S stratified sub-samples of every pixel, shape (H, W, S, S).

    ``offset`` moves the whole pixel grid by (dx, dy) pixels (used to build deliberately
    shifted images that show a test can tell a half-pixel shift); ``window = (row0, row1,
    col0, col1)`` keeps that block of pixels only.
    """
    width, height = image_size(name, n)
    row0, row1, col0, col1 = window or (0, height, 0, width)
    t = (np.arange(samples) + 0.5) / samples
    u = (np.arange(col0, col1)[None, :, None, None] + t[None, None, None, :] + offset[0]) / width
    v = (np.arange(row0, row1)[:, None, None, None] + t[None, None, :, None] + offset[1]) / height
    u, v = np.broadcast_arrays(u, v)
    return np.mod(u, 1.0), np.clip(v, 0.0, 1.0 - 1e-12)


def _weighted_mean(values, weights):
    """Per-pixel Σ w·value / Σ w over the two sub-sample axes; 0 where Σ w = 0."""
    wsum = weights.sum(axis=(2, 3))
    total = np.einsum("hwij,hwijc->hwc", weights, values)
    return np.where(wsum[..., None] > 0, total / np.where(wsum > 0, wsum, 1)[..., None], 0.0)


def _lookup(src, ix, iy):
    """Texels (ix, iy) of a lat-long, wrapping in longitude and continuing over the poles."""
    height, width = src.shape[:2]
    over_top = iy < 0
    over_bottom = iy >= height
    iy = np.where(over_top, -1 - iy, np.where(over_bottom, 2 * height - 1 - iy, iy))
    ix = np.where(over_top | over_bottom, ix + width // 2, ix)
    return src[iy, np.mod(ix, width)]


def sample_latlong(src: np.ndarray, dirs: np.ndarray, filt: str = "bilinear") -> np.ndarray:
    """Values (..., C) of lat-long ``src`` (H, 2H, C) in unit directions, read through ``filt``."""
    height, width = src.shape[:2]
    x, y, z = dirs[..., 0], dirs[..., 1], dirs[..., 2]
    u = 0.5 - np.arctan2(x, z) / (2 * math.pi)
    v = 0.5 - np.arcsin(np.clip(y, -1, 1)) / math.pi
    px, py = u * width, v * height
    if filt == "nearest":
        ix = np.minimum(np.floor(px).astype(int), width - 1)
        iy = np.minimum(np.floor(py).astype(int), height - 1)
        return _lookup(src, ix, iy)
    assert filt == "bilinear"
    fx, fy = px - 0.5, py - 0.5
    x0, y0 = np.floor(fx).astype(int), np.floor(fy).astype(int)
    tx, ty = (fx - x0)[..., None], (fy - y0)[..., None]
    return (
        (1 - tx) * (1 - ty) * _lookup(src, x0, y0)
        + tx * (1 - ty) * _lookup(src, x0 + 1, y0)
        + (1 - tx) * ty * _lookup(src, x0, y0 + 1)
        + tx * ty * _lookup(src, x0 + 1, y0 + 1)
    )


def naive_convert(src, to: str, n: int, samples: int = 1, filt="bilinear", rotation=None):
    """Resample a lat-long ``src`` (H, 2H, C) into layout ``to`` of size ``n``.

    For every output pixel: S×S sub-samples, each mapped to a direction, weighted by its solid
    angle, rotated into the source frame (L'(d) = L(Rᵀ d)) and read bilinearly from the
    source. Returns (pixels (H, W, C), alpha (H, W) = fraction of valid sub-samples).
    """
    u, v = subsample_uv(to, n, samples)
    dirs, valid, density = uv_to_dir(to, u, v)
    if rotation is not None:
        dirs = dirs @ np.asarray(rotation)  # row vector d → Rᵀ d
    values = sample_latlong(np.asarray(src, np.float64), dirs, filt)
    weights = np.where(valid, density, 0.0)
    return _weighted_mean(values, weights), valid.mean(axis=(2, 3))


def pixel_average(name: str, n: int, radiance, samples: int = 8, offset=(0.0, 0.0), window=None):
    """Solid-angle mean of ``radiance(dirs) -> (..., C)`` over every pixel of a layout.

    The heavily supersampled analytic image that a perfect converter would produce; with
    ``window = (row0, row1, col0, col1)``, only that block of it (the cost is the block's).
    """
    u, v = subsample_uv(name, n, samples, offset, window)
    dirs, valid, density = uv_to_dir(name, u, v)
    values = np.asarray(radiance(np.where(valid[..., None], dirs, [0.0, 0.0, 1.0])), np.float64)
    return _weighted_mean(values, np.where(valid, density, 0.0))


def pixel_solid_angles(name: str, n: int, samples: int = 8) -> np.ndarray:
    """Solid angle (sr) of the valid part of every pixel, by S×S midpoint sub-samples."""
    _, cols, rows, aspect, _ = GRIDS[name]
    u, v = subsample_uv(name, n, samples)
    _, valid, density = uv_to_dir(name, u, v)
    # One sub-sample covers (2 / (aspect N S)) × (2 / (N S)) of (a, b).
    area = (2.0 / (aspect * n * samples)) * (2.0 / (n * samples))
    return np.where(valid, density, 0.0).sum(axis=(2, 3)) * area
