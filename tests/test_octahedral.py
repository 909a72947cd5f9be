"""The octahedral and equal-area squares against truth envconv does not produce.

- Known directions at the centre, corners, edge midpoints, diagonals and half radii, written out
  from the definitions (docs/conventions.md repeats the table).
- The equal-area property: every pixel's solid angle as the area of the spherical polygon its
  boundary traces (envconv's own boundary directions, areas by spherical triangles).
- pbrt-v4's published functions and ``imgtool makeequiarea``, and RTXGI's octahedral functions
  and probe border update, re-expressed in numpy in ``tests/ports.py``.
"""

from __future__ import annotations

import math

import analytic
import naive
import numpy as np
import ports
import pytest
from conftest import detect_layout, rel_rms, run_cli, stderr_lines, write_plain

import envconv
from envconv.errors import LayoutError
from envconv.layouts.conventions import resolve_convention
from envconv.layouts.geometry import dir_to_uv, pixel_directions, pixel_solid_angles, uv_to_dir

SQUARES = ["octahedral", "equal-area"]
R2 = math.sqrt(0.5)
# (u, v) → direction, the same for both squares: centre, edge midpoints, corners, diagonals.
SHARED = [
    ((0.5, 0.5), (0, 1, 0)), ((1, 0.5), (1, 0, 0)), ((0, 0.5), (-1, 0, 0)),
    ((0.5, 0), (0, 0, 1)), ((0.5, 1), (0, 0, -1)),
    ((0, 0), (0, -1, 0)), ((1, 0), (0, -1, 0)), ((0, 1), (0, -1, 0)), ((1, 1), (0, -1, 0)),
    ((0.25, 0.25), (-R2, 0, R2)), ((0.75, 0.25), (R2, 0, R2)),
    ((0.25, 0.75), (-R2, 0, -R2)), ((0.75, 0.75), (R2, 0, -R2)),
]  # fmt: skip
# Half way from the centre to the right edge, and from (X − Z)/√2 to the corner: the octahedron
# points (1/2, 0, 1/2) and (1/4, 1/4, −1/2) of the papers' frame, or for the equal-area square
# the L1 radius r = 1/2, so |y| = 1 − r² = 3/4.
S = math.sqrt(1 - 0.75**2)
OWN = {
    "octahedral": [((0.75, 0.5), (R2, R2, 0)),
                   ((0.875, 0.875), np.array([1, -2, -1]) / math.sqrt(6))],
    "equal-area": [((0.75, 0.5), (S, 0.75, 0)), ((0.875, 0.875), (S * R2, -0.75, -S * R2))],
}  # fmt: skip


def _pbrt_to_envconv(e):
    """pbrt's light-frame direction e → the envconv direction of the same lat-long pixel:
    pbrt reads a lat-long at (SphericalPhi/2π, SphericalTheta/π) (imgtool makeequiarea), and
    docs/geometry.md says which direction that lat-long point is."""
    u = ports.spherical_phi(e) / (2 * math.pi)
    v = ports.spherical_theta(e) / math.pi
    return naive.face_to_dir("latlong", 0, 2 * u - 1, 2 * v - 1)


@pytest.mark.parametrize("name", SQUARES)
def test_square_points_hold_known_directions(name):
    points = SHARED + OWN[name]
    u = np.array([p[0] for p, _ in points], np.float64)
    v = np.array([p[1] for p, _ in points], np.float64)
    dirs, flags = uv_to_dir(name, u, v, size=16)
    assert np.all(flags == 2)
    for (uv, expected), got in zip(points, dirs, strict=True):
        np.testing.assert_allclose(got, expected, atol=1e-9, err_msg=str(uv))


@pytest.mark.parametrize("name", SQUARES)
def test_edges_fold_onto_themselves(name):
    """The two halves of each edge hold the same directions: (1, b) and (1, −b) are one."""
    t = np.linspace(0, 1, 41)
    for u, v, u2, v2 in [(np.ones_like(t), t, np.ones_like(t), 1 - t),
                         (t, np.zeros_like(t), 1 - t, np.zeros_like(t))]:  # fmt: skip
        a, _ = uv_to_dir(name, u, v, size=16)
        b, _ = uv_to_dir(name, u2, v2, size=16)
        np.testing.assert_allclose(a, b, atol=1e-9)


def _polygon_area(dirs):
    """Solid angle of the spherical polygon through unit vectors (K, 3), counter-clockwise or
    not: fan of triangles from the normalised mean, each by Van Oosterom & Strackee."""
    centre = dirs.mean(0)
    centre /= np.linalg.norm(centre)
    a, b = dirs, np.roll(dirs, -1, axis=0)
    num = np.einsum("ij,ij->i", np.broadcast_to(centre, a.shape), np.cross(a, b))
    den = 1 + a @ centre + b @ centre + np.einsum("ij,ij->i", a, b)
    return abs(2 * np.arctan2(num, den).sum())


def _pixel_areas(name, n, k):
    """Areas of every pixel's boundary polygon with k points per side, from envconv's map."""
    t = np.arange(k) / k
    out = np.zeros((n, n))
    for j in range(n):
        for i in range(n):
            x0, y0 = i / n, j / n
            side = 1 / n
            u = np.concatenate([x0 + side * t, np.full(k, x0 + side), x0 + side * (1 - t),
                                np.full(k, x0)])  # fmt: skip
            v = np.concatenate([np.full(k, y0), y0 + side * t, np.full(k, y0 + side),
                                y0 + side * (1 - t)])  # fmt: skip
            # A boundary on the image edge belongs to the pixel: nudge inwards by 1e-13.
            u = np.clip(u, 1e-13, 1 - 1e-13)
            v = np.clip(v, 1e-13, 1 - 1e-13)
            dirs, _ = uv_to_dir(name, u, v, size=n)
            out[j, i] = _polygon_area(dirs)
    return out


@pytest.mark.parametrize("n", [5, 8])
def test_every_equal_area_pixel_subtends_4pi_over_n2(n):
    """The boundary curves bend, so polygons with k and 2k points per side are extrapolated
    (Richardson, error ~ 1/k²); kinks of the map lie on pixel corners or side midpoints, which
    are sample points for even k."""
    coarse, fine = _pixel_areas("equal-area", n, 32), _pixel_areas("equal-area", n, 64)
    areas = (4 * fine - coarse) / 3
    np.testing.assert_allclose(areas, 4 * math.pi / n**2, rtol=1e-6)
    np.testing.assert_allclose(pixel_solid_angles("equal-area", n), 4 * math.pi / n**2, rtol=1e-12)
    # The octahedral square is not equal-area: its density varies fivefold (1 to 3√3).
    octa = (4 * _pixel_areas("octahedral", n, 64) - _pixel_areas("octahedral", n, 32)) / 3
    assert octa.max() / octa.min() > 2
    np.testing.assert_allclose(pixel_solid_angles("octahedral", n, samples=8), octa, rtol=3e-3)


def test_alpha_is_one_everywhere_in_the_square():
    """The squares have no invalid region: alpha is 1 in every pixel, 0 in a guard ring."""
    sky = envconv.EnvMap(np.ones((16, 32, 3), np.float32), "latlong")
    for name in SQUARES:
        out = envconv.convert(sky, name, size=9, samples=3, alpha=True)
        np.testing.assert_array_equal(out.pixels[..., 3], 1.0)
        guarded = envconv.convert(sky, name, size=9, samples=3, guard=2, alpha=True)
        alpha = guarded.pixels[..., 3]
        assert alpha.shape == (13, 13)
        np.testing.assert_array_equal(alpha[2:-2, 2:-2], 1.0)
        assert alpha.sum() == 81
        np.testing.assert_allclose(guarded.pixels[..., :3], 1.0, rtol=1e-6)  # guard holds data


# ---------------------------------------------------------------------------------------------
# pbrt-v4


def test_pbrt_preset_is_pbrt_square_to_sphere():
    """A pixel of a ``--out-convention pbrt`` square holds the lat-long's value in the direction
    pbrt's EqualAreaSquareToSphere gives it: w = M · d(p) equals the lat-long direction pbrt reads."""
    m = resolve_convention("pbrt", "equal-area").matrix
    rng = np.random.default_rng(7)
    p = np.concatenate([rng.random((2000, 2)), [[0.5, 0.5], [0, 0], [1, 0.5], [0.3, 1.0]]])
    d, _ = uv_to_dir("equal-area", p[:, 0], p[:, 1], size=32)
    pbrt = _pbrt_to_envconv(ports.equal_area_square_to_sphere(p))
    np.testing.assert_allclose(d @ m.T, pbrt, atol=1e-12)


def test_pbrt_preset_is_pbrt_sphere_to_square():
    """ImageInfiniteLight looks up EqualAreaSphereToSquare(w): envconv's inverse lands on the
    same point, within the 2.1e-6 of pbrt's atan polynomial."""
    m = resolve_convention("pbrt", "equal-area").matrix
    e = analytic.fibonacci_directions(4000)
    u, v = dir_to_uv("equal-area", _pbrt_to_envconv(e) @ m, size=32)
    got = np.stack([u, v], -1)
    expected = ports.equal_area_sphere_to_square(e)
    # Points on the square's edge have a folded twin; compare their directions instead.
    twin = np.abs(ports.equal_area_square_to_sphere(got) - e).max(-1) < 1e-12
    assert twin.all()
    assert np.abs(got - expected).max() < 2.2e-6


@pytest.fixture(scope="module")
def smooth_latlong():
    """64 × 128 lat-long of the smooth analytic environment (pixel averages)."""
    return naive.pixel_average("latlong", 64, analytic.smooth_radiance, 4)


def test_envconv_writes_the_square_makeequiarea_writes(smooth_latlong):
    """Same lat-long, same sub-sample points: envconv's solid-angle mean over each pixel is the
    plain mean, as in makeequiarea with a box filter. The difference left is the core's tile
    interpolation (sub-sample positions within 0.01 source texel, src/core/tiles.h), plus pbrt's
    clamp at the lat-long's first and last half-row. makeequiarea's own Gaussian (radius 1.5 px)
    blurs a little more; a transposed or unconverted square is far off."""
    n, s = 96, 4
    sky = envconv.EnvMap(smooth_latlong.astype(np.float32), "latlong")
    ours = envconv.convert(sky, "equal-area", size=n, samples=s, out_convention="pbrt",
                           filter="bilinear").pixels  # fmt: skip
    box = ports.make_equiarea(smooth_latlong, n, samples=s, filter="box")
    # Away from the lat-long's top and bottom half-row, where pbrt clamps and envconv continues
    # over the pole, the two bilinear reads are the same arithmetic.
    d = ports.equal_area_square_to_sphere(np.stack(np.meshgrid((np.arange(n) + 0.5) / n,
                                                               (np.arange(n) + 0.5) / n), -1))  # fmt: skip
    away = np.abs(d[..., 2]) < math.cos(1.5 * math.pi / 64)
    assert np.abs(ours - box)[away].max() < 5e-4 * np.abs(box).max()
    assert rel_rms(ours, box) < 1e-4
    gaussian = ports.make_equiarea(smooth_latlong, n, samples=8)
    blur = rel_rms(ours, gaussian)
    assert blur < 2e-3
    native = envconv.convert(sky, "equal-area", size=n, samples=s).pixels
    assert rel_rms(native, box) > 100 * blur
    assert rel_rms(np.swapaxes(ours, 0, 1), box) > 100 * blur


def test_pbrt_square_reads_back_as_pbrt_reads_it(smooth_latlong):
    """A square made by makeequiarea (the port), read with --in-convention pbrt and the nearest
    filter, gives each lat-long pixel the texel ImageInfiniteLight looks up for its direction."""
    n = 64
    square = ports.make_equiarea(smooth_latlong, n, samples=2, filter="box")
    env = envconv.EnvMap(square.astype(np.float32), "equal-area")
    back = envconv.convert(env, "latlong", size=48, samples=1, filter="nearest",
                           in_convention="pbrt").pixels  # fmt: skip
    dirs, _ = pixel_directions("latlong", 48)
    # The pbrt direction e whose lat-long point is envconv's d: invert _pbrt_to_envconv.
    e = np.stack([-dirs[..., 2], dirs[..., 0], dirs[..., 1]], -1)
    np.testing.assert_allclose(_pbrt_to_envconv(e), dirs, atol=1e-12)
    expected = ports.image_le(square, e)
    same = np.all(np.abs(back - expected) < 1e-6, axis=-1)
    assert same.mean() > 0.999  # the rest sit within pbrt's 2e-6 of a texel border


def test_cli_convert_to_pbrt_and_back(tmp_path, smooth_latlong):
    """The issue's command: the file is as wide as the lat-long, pixel centres read from it as
    makeequiarea's own points, and it reads back with --from equal-area --in-convention pbrt."""
    sky = tmp_path / "sky.exr"
    write_plain(sky, smooth_latlong)
    out = tmp_path / "sky_ea.exr"
    # The point kernel, as makeequiarea reads (the default area filter's box means differ
    # from its centre reads by 0.3 % RMS at this magnification).
    result = run_cli(["convert", sky, out, "--to", "equal-area", "--out-convention", "pbrt",
                      "--filter", "bilinear"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert stderr_lines(result) == []
    import OpenImageIO as oiio

    written = oiio.ImageBuf(str(out)).get_pixels(oiio.FLOAT)
    assert written.shape == (128, 128, 3)  # makeequiarea's default: the lat-long's width
    # At N = 128 from a 64-row lat-long, "auto" takes one sample, the pixel centre.
    centres = ports.make_equiarea(smooth_latlong, 128, samples=1, filter="box")
    assert rel_rms(written, centres) < 1e-4
    back = tmp_path / "back.exr"
    result = run_cli(["convert", out, back, "--to", "latlong", "--size", 64, "--from",
                      "equal-area", "--in-convention", "pbrt"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    truth = naive.pixel_average("latlong", 64, analytic.smooth_radiance, 8)
    plain = run_cli(["convert", out, tmp_path / "plain.exr", "--to", "latlong", "--size", 64,
                     "--from", "equal-area"])  # fmt: skip
    assert plain.exit_code == 0
    error = rel_rms(envconv.read(back).pixels, truth)
    assert error < 3e-3
    assert rel_rms(envconv.read(tmp_path / "plain.exr").pixels, truth) > 10 * error


def test_untagged_square_needs_from(tmp_path):
    with pytest.raises(LayoutError, match="sphere, angular, octahedral, equal-area or fisheye"):
        detect_layout(64, 64, {})
    path = tmp_path / "pbrt.exr"
    write_plain(path, np.ones((32, 32, 3)))
    result = run_cli(["convert", path, tmp_path / "o.exr", "--to", "latlong"])
    assert result.exit_code == 1
    assert len(stderr_lines(result)) == 1 and "--from" in result.stderr
    tagged = tmp_path / "tagged.exr"
    envconv.write(envconv.EnvMap(np.ones((32, 32, 3), np.float32), "equal-area"), tagged)
    assert envconv.read(tagged).layout.name == "equal-area"


def test_default_size_follows_the_preset():
    sky = envconv.EnvMap(np.ones((20, 40, 3), np.float32), "latlong")
    assert envconv.convert(sky, "equal-area", out_convention="pbrt").size == 40
    assert envconv.convert(sky, "equal-area").size != 40  # envconv's own rule: the horizon pitch


# ---------------------------------------------------------------------------------------------
# Guard rings: the fold, as pbrt wraps and RTXGI pads


@pytest.mark.parametrize("name", SQUARES)
@pytest.mark.parametrize("guard", [1, 3])
def test_guard_ring_is_the_mirrored_border(smooth_latlong, name, guard):
    """With one sample per pixel, a guard pixel holds the square's own pixel that pbrt's
    WrapEqualAreaSquare maps its centre to."""
    n = 12
    sky = envconv.EnvMap(smooth_latlong.astype(np.float32), "latlong")
    out = envconv.convert(sky, name, size=n, samples=1, guard=guard).pixels
    size = n + 2 * guard
    centres = (np.arange(size) + 0.5 - guard) / n
    u, v = np.meshgrid(centres, centres)
    wu, wv = ports.wrap_equal_area_square(u, v)
    i = np.floor(wu * n).astype(int) + guard
    j = np.floor(wv * n).astype(int) + guard
    np.testing.assert_allclose(out, out[j, i], rtol=1e-6)
    assert not np.allclose(out[0, guard:-guard], out[guard, guard:-guard])  # not a clamp


def test_one_pixel_guard_is_rtxgi_probe_border(smooth_latlong):
    """RTXGI's ProbeBorderUpdateCS pads each n×n probe to (n+2)²; envconv's guard=1 is the same."""
    sky = envconv.EnvMap(smooth_latlong.astype(np.float32), "latlong")
    for samples in (1, 3):
        probe = envconv.convert(sky, "octahedral", size=8, samples=samples, guard=1,
                                out_convention="ddgi").pixels  # fmt: skip
        np.testing.assert_allclose(probe, ports.ddgi_border_update(probe), rtol=1e-6)


def test_ddgi_preset_is_rtxgi_octahedral_direction():
    """Texel (i, j) of a ``ddgi`` file holds DDGIGetOctahedralDirection of its normalized
    coordinates, in a Y-up right-handed world (envconv's frame); ``ddgi-z-up`` in a Z-up one."""
    n = 10
    dirs, _ = pixel_directions("octahedral", n)
    jj, ii = np.mgrid[0:n, 0:n]
    t = ports.ddgi_direction(*ports.ddgi_normalized_coordinates(ii, jj, n))
    m = resolve_convention("ddgi", "octahedral").matrix
    np.testing.assert_allclose(dirs @ m.T, t, atol=1e-12)
    zup = resolve_convention("ddgi-z-up", "octahedral").matrix
    np.testing.assert_allclose(dirs @ zup.T, np.stack([t[..., 0], t[..., 2], -t[..., 1]], -1),
                               atol=1e-12)  # fmt: skip
    cx, cy = ports.ddgi_coordinates(t)
    u, v = dir_to_uv("octahedral", (t @ m), size=n)
    np.testing.assert_allclose(np.stack([u, v], -1), np.stack([(cx + 1) / 2, (cy + 1) / 2], -1),
                               atol=1e-12)  # fmt: skip


def test_both_squares_read_a_zero_component_as_positive():
    """The tie rule of the cube faces (a zero counts as positive) holds in both squares, for
    either sign of zero: -Y lands on the bottom-right corner (u, v) = (1, 1) in both, and a
    lower-hemisphere direction with t_x or t_y = ±0 on the same half of the edge in both
    (the halves (1, b) and (1, -b) hold the same direction; pbrt's copysign of -0 picked the
    other half in the equal-area square alone)."""
    from envconv.layouts.geometry import dir_to_uv

    zero = (0.0, -0.0)
    minus_y = np.array([(x, -1.0, z) for x in zero for z in zero])
    edges = np.array([(0.6, -0.8, z) for z in zero] + [(-0.6, -0.8, z) for z in zero]
                     + [(x, -0.8, 0.6) for x in zero] + [(x, -0.8, -0.6) for x in zero])  # fmt: skip
    signs = []
    for name in ("octahedral", "equal-area"):
        u, v = dir_to_uv(name, minus_y, size=8)
        np.testing.assert_array_equal(np.stack([u, v], -1), np.ones((4, 2)))
        u, v = dir_to_uv(name, edges, size=8)
        a, b = 2 * u - 1, 2 * v - 1
        # t = (d_x, -d_z, d_y): the zero component of t is read as positive.
        assert (a[[4, 5, 6, 7]] >= 0).all() and (b[[0, 1, 2, 3]] > 0).all(), (name, a, b)
        signs.append(np.sign(np.stack([a, b], -1)))
    np.testing.assert_array_equal(signs[0], signs[1])
