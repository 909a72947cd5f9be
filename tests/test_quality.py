"""Resampling quality at production sizes: no aliasing, highlights keep their energy, and the
tiled fast path of the kernel agrees with the naive per-sample reference.

Truth: analytic environments averaged over each output pixel (tests/naive.py), the analytic
solid angle of a lat-long texel, and tests/naive.py's independent resampler.
"""

from __future__ import annotations

import math
from pathlib import Path

import analytic
import naive
import numpy as np
import pytest

import envconv
from envconv.layouts.geometry import pixel_solid_angles
from envconv.resample.convert import default_size

# A pattern above every cube size's Nyquist limit below: cos(K lon) cos(K lat) has a period of
# 2π/K = 0.0245 rad, about one 64-pixel cube face pixel (≈ 0.026 rad) and 8 texels of the
# 2048 × 1024 source that holds it.
K = 256


def _pattern(dirs):
    d = np.asarray(dirs, np.float64)
    lon = np.arctan2(d[..., 0], d[..., 2])
    lat = np.arcsin(np.clip(d[..., 1], -1.0, 1.0))
    value = 0.5 + 0.5 * np.cos(K * lon) * np.cos(K * lat)
    return np.repeat(value[..., None], 3, axis=-1)


@pytest.fixture(scope="module")
def pattern_source():
    # Texel centres (8 a period): the defaults' result is 0.0021 RMS from the truth below (texel
    # means of 2 x 2 sub-samples: 0.0027), the single tap 0.22; 0.4 s to make instead of 2.3 s.
    return naive.pixel_average("latlong", 1024, _pattern, samples=1).astype(np.float32)


def test_high_frequency_pattern_does_not_alias(pattern_source):
    """The default (area) filter averages a pattern finer than the output pixels instead of
    aliasing.

    A single-tap bilinear converter (what most peers do) turns it into full-contrast moiré;
    the point kernel with samples=1 is asserted to, so this test can tell the two apart.
    """
    n = 64
    source = envconv.EnvMap(pattern_source, "latlong")
    truth = naive.pixel_average("cube-vcross", n, _pattern, samples=12)
    mask = naive.pixel_solid_angles("cube-vcross", n) > 0  # the six faces, not the empty cells

    def rms(result):
        return float(np.sqrt(np.mean((result.pixels[mask] - truth[mask]) ** 2)))

    converted = envconv.convert(source, "cube-vcross", size=n)
    single_tap = envconv.convert(source, "cube-vcross", size=n, samples=1, filter="bilinear")
    assert rms(converted) <= 0.02, rms(converted)
    assert rms(single_tap) >= 0.1, rms(single_tap)


def _checker(dirs, width=4096, check=4):
    """The lat-long-aligned checker of a width × width/2 image with ``check``-pixel squares,
    as a function of direction (1 on even squares, 0 on odd), from the lat-long formulas of
    docs/geometry.md: u = 0.5 − atan2(x, z) / 2π, v = 0.5 − asin(y) / π."""
    d = np.asarray(dirs, np.float64)
    u = 0.5 - np.arctan2(d[..., 0], d[..., 2]) / (2 * math.pi)
    v = 0.5 - np.arcsin(np.clip(d[..., 1], -1.0, 1.0)) / math.pi
    col = np.floor(u * width / check).astype(np.int64)
    row = np.floor(v * (width // 2) / check).astype(np.int64)
    value = ((col + row) % 2 == 0).astype(np.float64)
    return np.repeat(value[..., None], 3, axis=-1)


def _pixel_average_on_faces(name, n, radiance, samples, band=32):
    """naive.pixel_average over the layout's n × n cells that hold pixels, a band of rows at
    a time (the whole image would need gigabytes); 0 elsewhere."""
    width, height = naive.image_size(name, n)
    held = naive.pixel_solid_angles(name, n, samples=1) > 0
    out = np.zeros((height, width, 3))
    for row0 in range(0, height, n):
        for col0 in range(0, width, n):
            if not held[row0 : row0 + n, col0 : col0 + n].any():
                continue
            for top in range(row0, row0 + n, band):
                window = (top, min(top + band, row0 + n), col0, col0 + n)
                block = naive.pixel_average(name, n, radiance, samples, window=window)
                out[window[0] : window[1], col0 : col0 + n] = block
    return out


def test_checker_reduction_matches_the_analytic_pixel_average():
    """Issue 2's aliasing measure: a 4096 × 2048 lat-long of a checker with 4-pixel checks,
    converted to 128-pixel cube faces with the defaults, against the analytic mean of the
    checker over every cube pixel. RMS ≤ 0.013 (cmft's figure; single-tap peers reach 0.41)."""
    height = 2048
    jj, ii = np.mgrid[0:height, 0 : 2 * height]
    checker = (((ii // 4) + (jj // 4)) % 2 == 0).astype(np.float32)
    source = envconv.EnvMap(np.repeat(checker[..., None], 3, axis=2), "latlong")
    result = envconv.convert(source, "cube-vcross", size=128)
    truth = _pixel_average_on_faces("cube-vcross", 128, _checker, samples=16)
    faces = naive.pixel_solid_angles("cube-vcross", 128, samples=1) > 0
    rms = float(np.sqrt(np.mean((result.pixels[faces][:, 0] - truth[faces][:, 0]) ** 2)))
    assert rms <= 0.013, rms


def _psnr_tonemapped(test, reference):
    """PSNR (dB) of x / (1 + x) tone-mapped images, peak 1."""
    a = np.clip(test, 0, None) / (1 + np.clip(test, 0, None))
    b = np.clip(reference, 0, None) / (1 + np.clip(reference, 0, None))
    return 10 * math.log10(1.0 / np.mean((a.astype(np.float64) - b) ** 2))


@pytest.mark.parametrize("stem", ["park", "studio"])
def test_same_size_round_trip_is_as_sharp_as_single_tap(stem):
    """Issue 2: at 1:1, lat-long → cube → lat-long with the defaults (the area filter) scores at
    least as well (PSNR of x/(1+x)) as a correct single-tap bilinear converter (samples=1 on
    both legs, what skylibs does). 2×2 box-averaged bilinear taps, which soften, score visibly
    worse."""
    path = Path(__file__).resolve().parent.parent / "examples" / "data" / f"{stem}-latlong-512.exr"
    sky = envconv.read(path)

    def round_trip(samples, filter="bilinear"):
        cube = envconv.convert(sky, "cube-vcross", samples=samples, filter=filter)
        return envconv.convert(cube, "latlong", size=sky.size, samples=samples,
                               filter=filter).pixels  # fmt: skip

    reference = sky.pixels[..., :3]
    default = _psnr_tonemapped(round_trip("auto", "area")[..., :3], reference)
    single_tap = _psnr_tonemapped(round_trip(1)[..., :3], reference)
    boxed = _psnr_tonemapped(round_trip(2)[..., :3], reference)
    assert default >= single_tap - 0.05, (default, single_tap)
    assert boxed < single_tap - 0.3, (boxed, single_tap)


# A starfield: 300 one-texel highlights 10⁴ times their black surroundings. The area filter
# hands every texel's solid angle out exactly once, so their total is kept in a reduction into
# every layout within 0.5 %, under the defaults and with a fixed --samples (each sub-pixel
# integrated exactly). With one bilinear point sample per pixel it is not (asserted below, so
# the test can tell).
SPIKE_LAYOUTS = [n for n in envconv.layouts.LAYOUTS if n != "tennisball"]  # tennisball overlaps


@pytest.fixture(scope="module")
def starfield():
    height = 256
    rng = np.random.default_rng(7)
    rows, cols = rng.integers(0, height, 300), rng.integers(0, 2 * height, 300)
    texels = sorted(set(zip(rows.tolist(), cols.tolist(), strict=True)))
    pixels = np.zeros((height, 2 * height, 3), np.float32)
    rows = np.array([r for r, _ in texels], np.float64)
    pixels[rows.astype(int), [c for _, c in texels]] = 1e4
    # Analytic solid angle of a texel of row r: (2π / W) (sin lat_top − sin lat_bottom).
    lat_top = math.pi * (0.5 - rows / height)
    lat_bottom = math.pi * (0.5 - (rows + 1) / height)
    omega = 1e4 * (2 * math.pi / (2 * height)) * (np.sin(lat_top) - np.sin(lat_bottom))
    # A partial layout's default view sees the part of each highlight inside it: the texel's
    # own square (an isolated texel is reconstructed as a box), weighted by cos(latitude).
    t = (np.arange(32) + 0.5) / 32 - 0.5  # -0.5 … 0.5 texels from the texel's centre
    u = (np.array([c for _, c in texels])[:, None, None] + 0.5 + t[None, None, :]) / (2 * height)
    v = (rows[:, None, None] + 0.5 + t[None, :, None]) / height
    u, v = np.broadcast_arrays(u, v)
    dirs = naive.face_to_dir("latlong", 0, 2 * u - 1, 2 * v - 1)
    weight = np.abs(np.cos(np.pi * (0.5 - v)))
    seen = {name: (omega * (np.where(test(dirs), weight, 0).sum((1, 2)) / weight.sum((1, 2))))
            .sum() for name, test in naive.PARTIAL.items()}  # fmt: skip
    return envconv.EnvMap(pixels, "latlong"), {"whole": omega.sum(), **seen}


def _energy(envmap):
    omega = pixel_solid_angles(envmap.layout, envmap.size, envmap.guard, samples=8)
    return float((envmap.pixels[..., 0] * omega).sum())


@pytest.mark.parametrize("name", SPIKE_LAYOUTS)
@pytest.mark.parametrize("reduction", [4, 8])
def test_highlights_keep_their_energy_in_a_reduction(name, reduction, starfield):
    source, energies = starfield
    energy = energies.get(name, energies["whole"])  # a partial view: what it sees
    size = default_size(source, name) // reduction
    assert _energy(envconv.convert(source, name, size=size)) == pytest.approx(energy, rel=0.005)
    fixed = envconv.convert(source, name, size=size, samples=3)
    assert _energy(fixed) == pytest.approx(energy, rel=0.005)


def test_single_tap_loses_highlight_energy(starfield):
    """The same reduction with one bilinear point sample per pixel misses or doubles
    highlights (the point kernel; the area filter cannot: see above)."""
    source, energies = starfield
    energy = energies["whole"]
    errors = [
        abs(
            _energy(
                envconv.convert(
                    source, n, size=default_size(source, n) // 4, samples=1, filter="bilinear"
                )
            )  # fmt: skip
            - energy
        )
        / energy
        for n in ("latlong", "sphere", "paraboloid")
    ]
    assert max(errors) > 0.05, errors


@pytest.mark.parametrize(
    "name, n",
    [
        ("cube-vcross", 128),
        ("latlong", 64),
        ("sphere", 128),
        ("angular", 128),
        ("paraboloid", 96),
        ("tennisball", 96),
    ],
)
@pytest.mark.parametrize("samples", [1, 2])
def test_tiled_kernel_matches_naive(name, n, samples):
    """At these sizes most pixels take the kernel's interpolated-tile path (see
    src/core/tiles.h), which interpolates source positions and solid-angle weights;
    the result must still match the exact per-sample reference, near a mirror ball's rim
    (where the density is singular) as well."""
    source = naive.pixel_average("latlong", 128, analytic.radiance, 2).astype(np.float32)
    result = envconv.convert(envconv.EnvMap(source, "latlong"), name, size=n, samples=samples,
                             filter="bilinear")  # fmt: skip
    expected, _ = naive.naive_convert(source, name, n, samples)
    scale = np.abs(expected).max()
    np.testing.assert_allclose(result.pixels, expected, rtol=0, atol=2e-3 * scale)


@pytest.mark.parametrize("name, n", [("cube-vcross", 128), ("latlong", 64), ("octahedral", 96)])
@pytest.mark.parametrize("channels, alpha", [(4, False), (3, True)])
def test_single_sample_tiles_match_naive_as_stored(name, n, channels, alpha):
    """One sample a pixel on the interpolated-tile path, stored four floats at once (an RGBA
    map) or with the coverage after the colour (--alpha): each pixel is the bilinear read at
    its centre's direction, the exact per-sample reference's, in every channel."""
    rgb = naive.pixel_average("latlong", 128, analytic.radiance, 2)
    source = np.concatenate([rgb, rgb[..., :1] * 0.5 + 0.25], axis=-1)[..., :channels].astype(
        np.float32
    )
    result = envconv.convert(
        envconv.EnvMap(source, "latlong"),
        name,
        size=n,
        samples=1,
        alpha=alpha,
        filter="bilinear",
    )
    expected, coverage = naive.naive_convert(source, name, n, 1)
    scale = np.abs(expected).max()
    np.testing.assert_allclose(result.pixels[..., :channels], expected, rtol=0, atol=2e-3 * scale)
    if alpha:
        np.testing.assert_array_equal(result.pixels[..., 3], coverage.astype(np.float32))
