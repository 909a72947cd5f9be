"""--alpha: validity coverage, and its round trip through EXR, TIFF and PNG.

Coverage truth is computed here: the area of each pixel square inside the disks (by fine
midpoint integration, 64 × 64 points per pixel) or inside the occupied cells (exact), with
the cell tables of docs/geometry.md as written out in ``naive.GRIDS``.
"""

import math

import numpy as np
import pytest
from analytic import smooth_radiance
from naive import DISK_FAMILIES, GRIDS

import envconv
from envconv import io

N = 24


def analytic_coverage(name, n, g, fine=64):
    """Fraction of every pixel inside the valid region, (H, W) float64."""
    family, cols, rows, aspect, cells = GRIDS[name]
    cw, ch = aspect * n + 2 * g, n + 2 * g
    width, height = cols * cw, rows * ch
    if family not in DISK_FAMILIES:
        cover = np.zeros((height, width))
        for c, r, _, _ in cells:
            cover[r * ch + g : r * ch + g + n, c * cw + g : c * cw + g + aspect * n] = 1.0
        return cover
    t = (np.arange(fine) + 0.5) / fine
    xs = (np.arange(width)[:, None] + t[None, :]).ravel()
    ys = (np.arange(height)[:, None] + t[None, :]).ravel()
    inside = np.zeros((ys.size, xs.size), bool)
    for c, r, _, _ in cells:
        cx, cy = c * cw + g + n / 2, r * ch + g + n / 2
        inside |= (xs[None, :] - cx) ** 2 + (ys[:, None] - cy) ** 2 <= (n / 2) ** 2
    return inside.reshape(height, fine, width, fine).mean(axis=(1, 3))


@pytest.fixture(scope="module")
def sky():
    h = 64
    lat = math.pi * (0.5 - (np.arange(h) + 0.5) / h)
    lon = 2 * math.pi * (0.5 - (np.arange(2 * h) + 0.5) / (2 * h))
    lon, lat = np.meshgrid(lon, lat)
    dirs = np.stack([np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)], -1)
    return envconv.EnvMap((0.4 * smooth_radiance(dirs)).astype(np.float32), "latlong")


@pytest.mark.parametrize("guard", [0, 3])
@pytest.mark.parametrize("name", ["sphere", "angular", "paraboloid", "paraboloid-split"])
def test_disk_alpha_is_the_analytic_coverage(sky, name, guard):
    samples = 16
    out = envconv.convert(sky, name, size=N, samples=samples, guard=guard, alpha=True)
    assert out.channels[-1] == "A"
    alpha = out.pixels[..., -1].astype(np.float64)
    truth = analytic_coverage(name, N, guard)
    assert alpha.shape == truth.shape
    # Counted from S×S sub-samples: a pixel cut by the rim is off by at most about 1/S ...
    assert np.abs(alpha - truth).max() <= 1.5 / samples
    # ... and those counting errors cancel over the rim: the total is the disks' area.
    disks = len(GRIDS[name][4])
    assert alpha.sum() == pytest.approx(disks * math.pi * (N / 2) ** 2, rel=2e-3)
    # Wholly inside: 1; wholly outside (including the guard ring): 0.
    assert np.all(alpha[truth == 1.0] == 1.0)
    assert np.all(alpha[truth == 0.0] == 0.0)


@pytest.mark.parametrize("guard", [0, 2, "fill"])
@pytest.mark.parametrize(
    "name", ["cube-vcross", "cube-hcross", "cube-hstrip", "cube-exr", "latlong", "tennisball",
             "octahedral", "equal-area"]
)  # fmt: skip
def test_cell_alpha_is_exact(sky, name, guard):
    g = 0 if guard == "fill" else guard
    out = envconv.convert(sky, name, size=8, samples=3, guard=guard, alpha=True)
    np.testing.assert_array_equal(out.pixels[..., -1], analytic_coverage(name, 8, g))


def test_alpha_is_never_multiplied_into_colour(sky):
    with_alpha = envconv.convert(sky, "sphere", size=N, samples=4, guard="fill", alpha=True)
    without = envconv.convert(sky, "sphere", size=N, samples=4, guard="fill")
    np.testing.assert_array_equal(with_alpha.pixels[..., :3], without.pixels)
    partial = (with_alpha.pixels[..., 3] > 0) & (with_alpha.pixels[..., 3] < 1)
    assert partial.any() and np.all(with_alpha.pixels[partial][:, :3] > 0.05)


@pytest.mark.parametrize("name", ["cube-vcross", "sphere", "angular", "tennisball", "latlong"])
@pytest.mark.parametrize("samples", [None, 2])
def test_colour_is_the_same_whether_or_not_coverage_is_kept(sky, name, samples):
    """Without alpha (or mips) the kernel is given no coverage buffer; the colour it writes,
    empty cells included, must not change."""
    with_alpha = envconv.convert(sky, name, size=N, samples=samples, alpha=True)
    without = envconv.convert(sky, name, size=N, samples=samples)
    np.testing.assert_array_equal(with_alpha.pixels[..., :3], without.pixels)
    if name in ("cube-vcross", "sphere", "angular"):  # these have pixels outside the map
        assert with_alpha.pixels[..., 3].min() == 0.0


@pytest.mark.parametrize("ext, bit_depth", [("exr", "half"), ("exr", "float"), ("tif", "float"),
                                            ("tif", "uint16"), ("png", "uint8"), ("png", "uint16")])  # fmt: skip
def test_alpha_round_trips_without_touching_colour(sky, tmp_path, ext, bit_depth):
    # Fill gives colour where alpha is 0 or partial: a premultiplying reader or writer would
    # zero or scale exactly those pixels.
    env = envconv.convert(sky, "sphere", size=N, samples=4, guard="fill", alpha=True)
    assert env.pixels[..., :3].max() < 1.0  # representable in integer formats
    path = tmp_path / f"alpha.{ext}"
    io.write(env, path, bit_depth=bit_depth)
    back = io.read(path, layout="sphere")
    assert back.channels == ("R", "G", "B", "A")
    # Colour may only move by the format's quantisation (integer files hold sRGB codes, 8-bit
    # ones dithered); premultiplying would scale partial and zero-alpha pixels by alpha.
    colour_tol = {"half": 1e-3, "float": 1e-7, "uint16": 3e-4, "uint8": 0.02}[bit_depth]
    alpha_tol = {"half": 1e-3, "float": 1e-7, "uint16": 2 / 65535, "uint8": 1.01 / 255}[bit_depth]
    np.testing.assert_allclose(back.pixels[..., :3], env.pixels[..., :3], atol=colour_tol)
    np.testing.assert_allclose(back.pixels[..., 3], env.pixels[..., 3], atol=alpha_tol)


def test_input_alpha_is_carried_like_colour(sky):
    # An input alpha channel is resampled like any other channel (here: a smooth function),
    # and --alpha replaces it by the coverage.
    pixels = np.concatenate([sky.pixels, sky.pixels[..., :1]], axis=2)
    rgba = envconv.EnvMap(pixels, "latlong", channels=("R", "G", "B", "A"))
    cube = envconv.convert(rgba, "cube-hcross", size=8, samples=2)
    assert cube.channels == ("R", "G", "B", "A")
    np.testing.assert_allclose(cube.pixels[..., 3], cube.pixels[..., 0], atol=1e-6)
    masked = envconv.convert(rgba, "cube-hcross", size=8, samples=2, alpha=True)
    assert masked.channels == ("R", "G", "B", "A")
    np.testing.assert_array_equal(masked.pixels[..., 3], analytic_coverage("cube-hcross", 8, 0))


@pytest.mark.parametrize("name", ["sphere", "angular", "paraboloid", "cube-vcross"])
def test_pixels_outside_the_valid_region_are_ignored_on_input(sky, name):
    clean = envconv.convert(sky, name, size=32, samples=2)
    dirty = clean.pixels.copy()
    outside = analytic_coverage(name, 32, 0, fine=8) == 0
    dirty[outside] = 1e6
    a = envconv.convert(clean, "latlong", size=16, samples=2)
    b = envconv.convert(envconv.EnvMap(dirty, name), "latlong", size=16, samples=2)
    np.testing.assert_allclose(b.pixels, a.pixels, rtol=1e-5, atol=1e-6)


def test_a_channel_named_alpha_is_the_alpha_channel_everywhere(tmp_path):
    """One rule (envconv.envmap.is_alpha) for every reader of channel names: a lower-case
    'alpha' channel is overwritten by --alpha's coverage rather than joined by an A (resample
    and the plan agree), stored as unassociated alpha in a PNG, and read back as alpha."""
    import OpenImageIO as oiio

    from envconv.resample.options import output_channels

    pixels = np.ones((8, 16, 4), np.float32)
    source = envconv.EnvMap(pixels, "latlong", channels=("R", "G", "B", "alpha"))
    out = envconv.convert(source, "sphere", size=8, alpha=True)
    assert out.channels == output_channels(source.channels, True) == ("R", "G", "B", "alpha")
    coverage = out.pixels[..., 3]
    assert coverage[4, 4] == 1.0 and coverage[0, 0] < 0.5  # the disk's coverage, not the input
    path = tmp_path / "ball.png"
    envconv.write(out, path)
    assert oiio.ImageInput.open(str(path)).spec().alpha_channel == 3
    back = envconv.read(path, layout="sphere")
    assert back.alpha_index == 3
    rim = (back.pixels[..., 3] > 0.05) & (back.pixels[..., 3] < 0.95)
    # Stored unassociated: a rim pixel's colour is the constant 1, not 1 x its coverage.
    assert rim.any() and np.allclose(back.pixels[rim][:, :3], 1.0, atol=0.01)
