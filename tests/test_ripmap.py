"""The lat-long rip-map that auto sampling reads in polar rows (envconv.resample.kernels.build_rips).

Truth: numpy box averages of level 0, the seam-aware bilinear read of the core's taps
(the continued mapping that the known-direction tests pin to docs/geometry.md), and
analytic environments averaged over each output pixel (tests/naive.py).
"""

from __future__ import annotations

import math

import naive
import numpy as np
import pytest

import envconv
from envconv.layouts.geometry import kernel_geometry
from envconv.resample import kernels
from envconv.resample.kernels import (
    FILTER_BILINEAR,
    build_rips,
    filtered_reads,
    level_reads,
    resample_rows,
    rip_level_count,
    rip_offset,
)


def _level_read(rip, start, width, x, y):
    return level_reads(rip, start, width, [(x, y)])[0]


def _seam_aware_read(src, geometry, x, y):
    return filtered_reads(src, geometry, [0], [(x, y)], FILTER_BILINEAR)[0]


@pytest.mark.parametrize(
    "width, levels", [(32, 2), (24, 1), (20, 1), (12, 0), (2048, 8), (6144, 8), (6, 0)]
)
def test_level_count_stops_at_odd_or_narrow_levels(width, levels):
    """A level needs an even width (the pole continuation shifts by half of it) of at least 8,
    and there are at most 8 levels."""
    assert rip_level_count(width) == levels


def test_levels_are_box_averages_of_level_0():
    rng = np.random.default_rng(1)
    src = rng.random((16, 64, 3)).astype(np.float32) * 100
    rip, levels = build_rips(src)
    assert levels == 3
    assert rip.shape == (16, 64 - 64 // 8, 3)
    for k in range(1, levels + 1):
        width = 64 >> k
        start = rip_offset(64, k)
        expected = src.astype(np.float64).reshape(16, width, 2**k, 3).mean(axis=2)
        np.testing.assert_allclose(rip[:, start : start + width], expected, rtol=1e-6)
        # Box averages keep every row's sum: no energy gained or lost.
        np.testing.assert_allclose(
            rip[:, start : start + width].sum(axis=1) * 2**k, src.sum(axis=1), rtol=1e-5
        )


def test_no_levels_for_a_width_that_cannot_hold_one():
    rip, levels = build_rips(np.ones((6, 12, 3), np.float32))
    assert levels == 0


def test_level_tap_on_level_0_matches_the_seam_aware_bilinear_read():
    """level_tap's own wrap and pole continuation agree with the kernel's continued mapping,
    everywhere and in particular across the wrap and past both poles."""
    rng = np.random.default_rng(2)
    height, width = 16, 32
    src = rng.random((height, width, 3)).astype(np.float32)
    layout = envconv.layouts.get_layout("latlong")
    geometry = kernel_geometry(layout, height, 0)
    xs = np.concatenate([rng.uniform(0, width, 200), [0.0, 0.1, 0.5, 31.6, 31.99]])
    ys = np.concatenate([rng.uniform(0, height, 200), [0.0, 0.2, 15.9, 16.0, 8.0]])
    for x, y in zip(xs, ys, strict=True):
        got = _level_read(src, 0, width, x, y)
        expected = _seam_aware_read(src, geometry, x, y)
        np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-7, err_msg=f"{x}, {y}")


def test_level_tap_reads_box_averages_and_wraps_on_a_level():
    rng = np.random.default_rng(3)
    src = rng.random((8, 64, 1)).astype(np.float32)
    rip, _ = build_rips(src)
    k, width = 2, 16
    start = rip_offset(64, k)
    boxes = src[:, :, 0].astype(np.float64).reshape(8, width, 4).mean(axis=2)
    # At a texel centre: that box's mean.
    np.testing.assert_allclose(_level_read(rip, start, width, 5.5, 3.5)[0], boxes[3, 5], rtol=1e-6)
    # A quarter texel past the last column: wraps to the first.
    expected = 0.75 * boxes[3, 15] + 0.25 * boxes[3, 0]
    np.testing.assert_allclose(_level_read(rip, start, width, 15.75, 3.5)[0], expected, rtol=1e-6)
    # Above the first row: row 0, half a turn away.
    expected = 0.5 * boxes[0, 2] + 0.5 * boxes[0, (2 + width // 2) % width]
    np.testing.assert_allclose(_level_read(rip, start, width, 2.5, 0.0)[0], expected, rtol=1e-6)


# Longitudinal stripes: cos(K lon) converges on the poles, so near them a cube pixel spans
# many periods along x and a handful of texels along y: the case the rip-map is for.
K = 96


def _stripes(dirs):
    d = np.asarray(dirs, np.float64)
    lon = np.arctan2(d[..., 0], d[..., 2])
    value = 1.0 + 0.9 * np.cos(K * lon)
    return np.repeat(value[..., None], 3, axis=-1)


@pytest.fixture(scope="module")
def stripes_source():
    return naive.pixel_average("latlong", 512, _stripes, samples=2).astype(np.float32)


def _convert_without_rips(source, n, samples):
    to = envconv.layouts.get_layout("cube-vcross")
    width, height = to.image_size(n)
    out = np.empty((height, width, 3), np.float32)
    alpha = np.empty((height, width), np.float32)
    dgeo = kernel_geometry(to, n, 0)
    sgeo = kernel_geometry(source.layout, source.size, 0)
    no_rips = np.zeros((1, 1, 3), np.float32)
    resample_rows(
        source.pixels, no_rips, 0, 0, sgeo, dgeo, 1.0, 1.0, samples, 1, np.eye(3), False, out,
        alpha,
    )  # fmt: skip
    return out


#: Size of the cube-vcross the polar-cap tests make, and its +Y (top) and -Y (bottom) faces
#: as (row0, row1, col0, col1).
CAP_SIZE = 48
CAPS = [(0, CAP_SIZE, CAP_SIZE, 2 * CAP_SIZE), (2 * CAP_SIZE, 3 * CAP_SIZE, CAP_SIZE, 2 * CAP_SIZE)]


@pytest.fixture(scope="module")
def caps_truth():
    """The analytic pixel average of the stripes over the caps (24 × 24 sub-samples a pixel)."""
    return [naive.pixel_average("cube-vcross", CAP_SIZE, _stripes, 24, window=cap) for cap in CAPS]


def _caps_rms(pixels, truth) -> float:
    """RMS error of a cube-vcross's caps against ``truth``."""
    error = [pixels[r0:r1, c0:c1] - t for (r0, r1, c0, c1), t in zip(CAPS, truth, strict=True)]
    return float(np.sqrt(np.mean(np.square(error))))


def test_polar_caps_read_through_the_rip_map_match_the_pixel_average(stripes_source, caps_truth):
    """The top and bottom faces, read through the rip-map, are as close to the analytic pixel
    average as brute-force sub-sampling of level 0, and far from single-tap moiré."""
    n = CAP_SIZE
    source = envconv.EnvMap(stripes_source, "latlong")

    def rms(pixels):
        return _caps_rms(pixels, caps_truth)

    with_rips = rms(envconv.convert(source, "cube-vcross", size=n, filter="bilinear").pixels)
    brute_force = rms(_convert_without_rips(source, n, 0))
    single_tap = rms(_convert_without_rips(source, n, 1))
    assert with_rips <= max(1.25 * brute_force, 0.01), (with_rips, brute_force)
    assert single_tap >= 10 * with_rips, (single_tap, with_rips)
    assert not math.isnan(with_rips)


def test_only_the_polar_rows_are_filled_and_they_equal_a_full_build():
    rng = np.random.default_rng(2)
    src = rng.random((32, 64, 3)).astype(np.float32)
    full, levels = build_rips(src)
    poisoned = np.full_like(full, np.nan)
    partial, _ = build_rips(src, rows=5, out=poisoned)
    filled = np.zeros(32, bool)
    filled[:5] = filled[-5:] = True
    np.testing.assert_array_equal(partial[filled], full[filled])
    assert np.isnan(partial[~filled]).all()


def _poisoned_rips(monkeypatch, rows=None):
    """Make source_rips fill unfilled rip-map rows with NaN, and optionally fix the row count."""
    import envconv.resample.convert as resample_module

    original = kernels.build_rips

    def poisoned(src, rows=None, out=None):
        height, width, nch = src.shape
        levels = rip_level_count(width)
        shape = (height, width - (width >> levels), nch)
        return original(src, rows, np.full(shape, np.nan, np.float32))

    monkeypatch.setattr(kernels, "build_rips", poisoned)
    if rows is not None:
        monkeypatch.setattr(resample_module, "rip_rows", lambda *args: rows)


@pytest.mark.parametrize(
    "to, size, rotate",
    [("cube-vcross", 128, None), ("latlong", 192, (20, 35, 10)), ("paraboloid", 256, (0, 60, 0))],
)
def test_rows_filled_near_the_poles_give_the_pixels_of_a_full_rip_map(
    stripes_source, monkeypatch, to, size, rotate
):
    """The estimate of rows a conversion reads through the rip-map covers what it reads: the
    pixels are those of a rip-map filled in every row, bit for bit, and none is NaN although
    the unfilled rows are. (Each case fills under half the rows, and reads the rip-map: without
    it the pixels differ.)"""
    import envconv.resample.convert as resample_module

    source = envconv.EnvMap(stripes_source, "latlong")
    height, width = stripes_source.shape[:2]
    assert 2 * resample_module.rip_rows(width, height, to, size) < height
    with monkeypatch.context() as patch:
        patch.setattr(resample_module, "rip_rows", lambda *args: height)
        expected = envconv.convert(source, to, size=size, rotate=rotate, filter="bilinear").pixels
        patch.setattr(resample_module, "rip_rows", lambda *args: 0)
        level_0 = envconv.convert(source, to, size=size, rotate=rotate, filter="bilinear").pixels
    assert (level_0 != expected).any()
    _poisoned_rips(monkeypatch)
    got = envconv.convert(source, to, size=size, rotate=rotate, filter="bilinear").pixels
    np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("to", ["cube-vcross", "sphere", "angular"])
def test_pixels_that_could_reach_an_unfilled_row_read_level_0(
    stripes_source, caps_truth, monkeypatch, to
):
    """With only 4 rows filled at each pole (far fewer than the caps need), the kernel must
    never read the others: no NaN, and the polar caps stay as close to the analytic pixel
    average as brute-force sub-sampling."""
    n = CAP_SIZE
    source = envconv.EnvMap(stripes_source, "latlong")
    _poisoned_rips(monkeypatch, rows=4)
    got = envconv.convert(source, to, size=n, filter="bilinear").pixels
    assert np.isfinite(got).all()
    if to == "cube-vcross":
        rms = _caps_rms(got, caps_truth)
        brute = _caps_rms(_convert_without_rips(source, n, 0), caps_truth)
        assert rms <= max(1.25 * brute, 0.01), (rms, brute)
