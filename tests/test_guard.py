"""Guard rings and --guard fill against the analytic environment in the continued direction.

The continued direction of every pixel is computed here from docs/geometry.md ("Guard ring"),
with numpy and the cell tables of ``naive.GRIDS``; nothing in envconv's geometry is called.
Conversions use the point kernel with one sub-sample per pixel (the pixel centre), so each
output pixel must equal the source environment in its pixel centre's continued direction. The
area filter's ring (the default) is tested at the end: its cells are the ringless map's, its
ring what a bilinear lookup of that map reads across the edge.
"""

import math

import numpy as np
import pytest
from analytic import smooth_radiance
from naive import DISK_FAMILIES, GRIDS
from naive import face_to_dir as naive_face_to_dir

import envconv
from envconv import io

N = 16
ALL_LAYOUTS = list(GRIDS)


def _continued_dir(family, face, a, b):
    """Cell mapping continued past the valid region (sphere rule written out separately)."""
    if family != "sphere":
        return naive_face_to_dir(family, face, a, b)
    X, Y = a, -b
    r = np.sqrt(X * X + Y * Y)
    inside = naive_face_to_dir(family, face, np.clip(a, -1, 1), np.clip(b, -1, 1))
    rc = np.clip(r, 1.0, 2.0)
    alpha = 2 * math.pi - 2 * np.arcsin(2.0 - rc)
    s = np.sin(alpha) / np.where(r > 0, r, 1.0)
    past = np.stack([s * X, s * Y, np.cos(alpha)], -1)
    return np.where((r <= 1.0)[..., None], inside, past)


def guarded_geometry(name, n, g, fill=False):
    """Pixel-centre directions (H, W, 3) and region (H, W): 2 valid, 1 guard or fill, 0 none."""
    family, cols, rows, aspect, cells = GRIDS[name]
    disk = family in DISK_FAMILIES
    cw, ch = aspect * n + 2 * g, n + 2 * g
    x, y = np.meshgrid(np.arange(cols * cw) + 0.5, np.arange(rows * ch) + 0.5)
    dirs = np.zeros(x.shape + (3,))
    region = np.zeros(x.shape, int)
    best = np.full(x.shape, np.inf)
    local = []
    for c, r, f, rotated in cells:
        a = 2 * (x - c * cw - g) / (aspect * n) - 1
        b = 2 * (y - r * ch - g) / n - 1
        if rotated:
            a, b = -a, -b
        here = (x // cw == c) & (y // ch == r)
        if disk:
            radius = np.sqrt(a * a + b * b)
            valid = here & (radius <= 1.0)
            readable = here & (radius <= 1.0 + 2.0 * g / n)
            distance = np.maximum(
                np.hypot(x - (c * cw + g + n / 2), y - (r * ch + g + n / 2)) - n / 2, 0
            )
        else:
            valid = here & (np.abs(a) <= 1) & (np.abs(b) <= 1)
            readable = here
            x0, y0 = c * cw + g, r * ch + g
            dx = np.maximum.reduce([x0 - x, np.zeros_like(x), x - (x0 + aspect * n)])
            dy = np.maximum.reduce([y0 - y, np.zeros_like(y), y - (y0 + n)])
            distance = np.hypot(dx, dy)
        d = _continued_dir(family, np.full(x.shape, f), a, b)
        dirs = np.where(readable[..., None], d, dirs)
        region = np.where(valid, 2, np.where(readable, 1, region))
        local.append((f, distance, d))
    if fill:
        empty = region == 0
        choice = np.zeros(x.shape, int)
        for k, (_face, distance, _) in sorted(enumerate(local), key=lambda item: item[1][0]):
            closer = distance < best
            choice = np.where(closer, k, choice)
            best = np.where(closer, distance, best)
        for k, (_, _, d) in enumerate(local):
            dirs = np.where((empty & (choice == k))[..., None], d, dirs)
        region = np.where(empty, 1, region)
    return dirs, region


@pytest.fixture(scope="module")
def sky():
    """Lat-long 512 × 256 of the smooth analytic environment at pixel centres."""
    h = 256
    lat = math.pi * (0.5 - (np.arange(h) + 0.5) / h)
    lon = 2 * math.pi * (0.5 - (np.arange(2 * h) + 0.5) / (2 * h))
    lon, lat = np.meshgrid(lon, lat)
    dirs = np.stack([np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)], -1)
    return envconv.EnvMap(smooth_radiance(dirs).astype(np.float32), "latlong")


TOLERANCE = 2e-3  # bilinear reconstruction of a 256-row lat-long of a smooth environment


@pytest.mark.parametrize("guard", [2, "fill"])
@pytest.mark.parametrize("name", ALL_LAYOUTS)
def test_guard_pixels_hold_the_continued_direction(sky, name, guard):
    fill = guard == "fill"
    out = envconv.convert(sky, name, size=N, samples=1, guard=guard, alpha=True, filter="bilinear")
    dirs, region = guarded_geometry(name, N, 0 if fill else guard, fill)
    assert out.pixels.shape[:2] == region.shape
    truth = smooth_radiance(np.where(region[..., None] > 0, dirs, [0.0, 0.0, 1.0]))
    error = np.abs(out.pixels[..., :3] - truth).max(axis=-1)
    interior, ring = error[region == 2], error[region == 1]
    assert interior.max() < TOLERANCE
    if ring.size:
        assert ring.max() < TOLERANCE, (
            f"guard error {ring.max():.2e} vs interior {interior.max():.2e}"
        )
    # No data where neither valid nor guard; alpha marks the valid region only.
    assert np.all(out.pixels[region == 0] == 0)
    # With one sub-sample per pixel, alpha is 1 exactly where the centre is valid: guard and
    # fill pixels have alpha 0.
    np.testing.assert_array_equal(out.pixels[..., 3], (region == 2).astype(np.float32))


@pytest.mark.parametrize("name", ["cube-hcross", "cube-vcross", "paraboloid", "angular"])
def test_fill_covers_the_whole_image(sky, name):
    out = envconv.convert(sky, name, size=N, samples=2, guard="fill")
    assert np.all(out.pixels > 0.05)  # smooth_radiance is at least ~0.2 everywhere


@pytest.mark.parametrize(
    "name, guard", [("cube-vcross", 3), ("paraboloid", 2), ("sphere", 2), ("tennisball", 1),
                    ("latlong", 2), ("cube-exr", 2)]
)  # fmt: skip
def test_guarded_file_reads_as_the_same_environment(sky, tmp_path, name, guard):
    plain, guarded = tmp_path / "plain.exr", tmp_path / "guarded.exr"
    io.write(envconv.convert(sky, name, size=N, samples=2), plain, bit_depth="float")
    io.write(envconv.convert(sky, name, size=N, samples=2, guard=guard), guarded, bit_depth="float")
    a, b = io.read(plain, layout=name), io.read(guarded)
    assert (b.layout.name, b.guard, b.size) == (name, guard, N)
    la = envconv.convert(a, "latlong", size=32, samples=2)
    lb = envconv.convert(b, "latlong", size=32, samples=2)
    h = 32
    lat = math.pi * (0.5 - (np.arange(h) + 0.5) / h)
    lon = 2 * math.pi * (0.5 - (np.arange(2 * h) + 0.5) / (2 * h))
    lon, lat = np.meshgrid(lon, lat)
    dirs = np.stack([np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)], -1)
    truth = smooth_radiance(dirs)
    # A 16-pixel mirror ball cannot resolve anything near -Z (its rim), guard or not.
    resolved = dirs[..., 2] > -0.5 if name == "sphere" else np.ones(dirs.shape[:2], bool)
    scale = np.abs(la.pixels).max()
    assert np.abs(la.pixels - lb.pixels)[resolved].max() < 0.02 * scale
    # Both agree with the truth about equally well.
    err_a = np.abs(la.pixels - truth).mean()
    err_b = np.abs(lb.pixels - truth).mean()
    assert err_b <= 1.5 * err_a + 1e-4


def test_guard_grows_every_cell():
    sky = envconv.EnvMap(np.ones((8, 16, 3), np.float32), "latlong")
    assert envconv.convert(sky, "cube-vcross", size=10, guard=3).pixels.shape[:2] == (64, 48)
    assert envconv.convert(sky, "paraboloid", size=254, samples=1, guard=1).pixels.shape[:2] == (
        256,
        512,
    )
    assert envconv.convert(sky, "latlong", size=10, guard=2).pixels.shape[:2] == (14, 24)
    assert envconv.convert(sky, "tennisball", size=10, guard=2).pixels.shape[:2] == (28, 34)
