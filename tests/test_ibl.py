"""GGX-prefiltered chains and irradiance maps (envconv.resample.ibl, src/core/ibl.*) against truth.

The truth is a brute-force integral of the analytic environment (tests/ggx_reference.py),
computed here for a fixed sample of texels of every level.
"""

from __future__ import annotations

import math

import analytic
import naive
import numpy as np
import pytest
from conftest import run_cli
from ggx_reference import disk_environment, ggx_reference, lobe_integral_at, texel_mean
from node_readers import read_container

import envconv
from envconv.errors import UsageError
from envconv.resample.ibl import roughness_levels

N = 32  # output faces: levels 32, 16, 8, 4, 2, 1
SUN = analytic.SUN / np.linalg.norm(analytic.SUN)


def _source(fn, height=128):
    return envconv.EnvMap(naive.pixel_average("latlong", height, fn, samples=6).astype(np.float32),
                          "latlong")  # fmt: skip


def _texels(size, count, rng, near=None):
    every = np.stack(np.meshgrid(np.arange(6), np.arange(size), np.arange(size), indexing="ij"),
                     -1).reshape(-1, 3)  # fmt: skip
    pick = every if len(every) <= count else every[rng.choice(len(every), count, replace=False)]
    if near is not None and len(every) > count:  # and the texels nearest the disk
        centres = texel_mean(lambda d: d, size, every, samples=1)
        pick = np.concatenate([pick, every[np.argsort(-(centres @ near))[: count // 4]]])
    return pick


def _level_texels(level, size, texels):
    faces = level.reshape(size, 6, size, -1)
    return faces[texels[:, 1], texels[:, 0], texels[:, 2]]


def test_roughness_mappings():
    assert roughness_levels("gltf", 9) == [k / 8 for k in range(9)]
    filament = roughness_levels("filament", 5)  # lod = r (2 - r) at lod = k / 4
    assert [round(r * (2 - r), 12) for r in filament] == [0, 0.25, 0.5, 0.75, 1.0]
    unreal = roughness_levels("unreal", 9)  # 2^((1 - (8 - k)) / 1.2), at most 1
    assert unreal[0] == 0 and unreal[7] == unreal[8] == 1.0
    assert unreal[6] == pytest.approx(2 ** (-1 / 1.2)) and unreal[1] == pytest.approx(
        2 ** (-6 / 1.2)
    )
    assert roughness_levels([0.2, 0.4], 3) == [0.0, 0.2, 0.4]
    with pytest.raises(UsageError):
        roughness_levels([0.2], 3)
    with pytest.raises(UsageError):
        roughness_levels("phong", 3)


@pytest.mark.parametrize("layout", ["cube-faces", "latlong", "paraboloid", "cube-vcross"])
def test_rough_level_of_a_constant_environment_is_that_constant(layout):
    sky = envconv.EnvMap(np.full((32, 64, 3), [2.5, 1.0, 0.25], np.float32), "latlong")
    chain = envconv.convert(sky, layout, size=16, mips="ggx", alpha=True)
    for level in chain.levels[1:]:
        valid = level[:, :, 3] > 0
        np.testing.assert_allclose(level[valid][:, :3], [[2.5, 1.0, 0.25]] * valid.sum(), rtol=1e-5)
    # The small sky is resampled onto the irradiance pyramid, the large one binned into it.
    for height in (32, 512):
        sky = envconv.EnvMap(np.full((height, 2 * height, 3), [2.5, 1.0, 0.25], np.float32),
                             "latlong")  # fmt: skip
        irr = envconv.convert(sky, layout, size=8, irradiance=True, alpha=True)
        valid = irr.pixels[:, :, 3] > 0
        np.testing.assert_allclose(
            irr.pixels[valid][:, :3], [[2.5, 1.0, 0.25]] * valid.sum(), rtol=1e-5
        )


QUADRATURE = dict(n_xi=32, n_phi=32, n_r=24, n_psi=48)


def _check_accuracy(chain, smooth, disk, mean_radiance):
    rng = np.random.default_rng(7)
    rough = [float(r) for r in chain.metadata["envconv:roughness"].split()]
    for k in range(1, len(chain.levels)):
        size = N >> k
        alpha = rough[k] ** 2
        texels = _texels(size, 160, rng, None if disk is None else disk[0])
        # 32 x 32 half-vector and 24 x 48 disk nodes: within 0.08 % of 48 x 48 and 32 x 64
        # (measured on both environments below), 50 times under the 5 % allowed, 3 times faster.
        truth = texel_mean(lambda d, a=alpha: ggx_reference(d, a, smooth, disk, **QUADRATURE),
                           size, texels)  # fmt: skip
        got = _level_texels(chain.levels[k], size, texels)
        rms = np.sqrt(((got - truth) ** 2).sum() / (truth**2).sum())
        worst = np.abs(got - truth).max() / np.abs(truth).max(axis=1).min()
        worst = (np.abs(got - truth) / np.abs(truth)).max()
        assert rms <= 0.01, (k, rms)
        assert worst <= 0.05, (k, worst)
        omega = naive.pixel_solid_angles("cube-faces", size, samples=8)
        energy = (chain.levels[k] * omega[..., None]).sum((0, 1)) / (4 * math.pi)
        np.testing.assert_allclose(energy, mean_radiance, rtol=0.005, err_msg=f"level {k}")


@pytest.mark.slow
def test_ggx_chain_of_a_smooth_environment_matches_the_integral():
    chain = envconv.convert(_source(analytic.smooth_radiance), "cube-faces", size=N, mips="ggx")
    _check_accuracy(chain, analytic.smooth_radiance, None,
                    analytic.sphere_mean(analytic.smooth_radiance))  # fmt: skip


@pytest.mark.slow
def test_ggx_chain_of_a_bright_disk_matches_the_integral():
    def base(d):
        return 0.5 * analytic.smooth_radiance(d)

    radiance, disk = disk_environment(base, SUN, 0.08, [60.0, 50.0, 40.0])
    source = _source(radiance, height=256)
    chain = envconv.convert(source, "cube-faces", size=N, mips="ggx")
    disk_mean = np.asarray(disk[2]) * 2 * math.pi * (1 - math.cos(0.08)) / (4 * math.pi)
    _check_accuracy(chain, base, disk, analytic.sphere_mean(base) + disk_mean)


def test_one_texel_sun_makes_no_fireflies():
    """A single bright texel of a cube source: every level is the lobe integrated over that
    texel (16 x 16 point sources), never below the background, nowhere brighter."""
    pixels = np.ones((16, 96, 3), np.float32)
    pixels[5, 4 * 16 + 9] = 5000.0  # face +Z_c, row 5, column 9
    source = envconv.EnvMap(pixels, "cube-faces")
    o = (np.arange(16) + 0.5) / 16
    a, b = np.meshgrid(-1 + 2 * (9 + o) / 16, -1 + 2 * (5 + o) / 16)
    suns = naive.face_to_dir("cube", np.full(a.shape, 4), a, b).reshape(-1, 3)
    weights = (naive.face_density("cube", 4, a, b) * (2 / 256) ** 2).ravel()
    chain = envconv.convert(
        source, "cube-faces", size=16, mips="ggx", roughness=[0.5, 0.6, 0.8, 1.0]
    )
    rough = [float(r) for r in chain.metadata["envconv:roughness"].split()]
    for k in range(1, len(chain.levels)):
        size = 16 >> k
        texels = np.stack(np.meshgrid(np.arange(6), np.arange(size), np.arange(size),
                                      indexing="ij"), -1).reshape(-1, 3)  # fmt: skip
        alpha = rough[k] ** 2
        t = 1 - (1 - np.linspace(0, 1, 200001)) ** 3  # ∫ D (n·l)⁺ dl = 2π ∫ K(t) dt, zonal
        a2 = alpha * alpha
        norm = 2 * math.pi * np.trapezoid(a2 * t / (np.pi * ((1 + t) / 2 * (a2 - 1) + 1) ** 2), t)

        def point(d, a=alpha, z=norm):
            lobe = lobe_integral_at(d, suns, weights, a)[:, None]
            return 1.0 + (5000.0 - 1.0) * lobe / z * np.ones(3)

        truth = texel_mean(point, size, texels, samples=8)
        got = _level_texels(chain.levels[k], size, texels)
        assert got.min() >= 1.0 - 1e-4
        assert np.sqrt(((got - truth) ** 2).sum() / (truth**2).sum()) < 0.04, k
        assert got.max() <= truth.max() * 1.05


def test_chain_of_a_rotated_map_equals_the_rotated_chain():
    source = _source(analytic.radiance)
    turned = envconv.convert(source, "cube-faces", size=16, mips="ggx", rotate="90,0,0")
    reference = _source(lambda d: analytic.radiance(d @ _yaw(90)))  # L(Rᵀ d), rows
    expected = envconv.convert(reference, "cube-faces", size=16, mips="ggx")
    for got, want in zip(turned.levels[1:], expected.levels[1:], strict=True):
        assert np.sqrt(((got - want) ** 2).sum() / (want**2).sum()) < 0.01


def _yaw(degrees):
    from envconv.layouts.rotation import rotation_matrix

    return rotation_matrix(degrees, 0, 0)


def test_irradiance_matches_the_sh_irradiance_of_a_low_order_environment():
    """For an environment of SH order ≤ 2 the R&H irradiance is exact: E/π from the cosine
    convolution must equal it."""

    def low(d):
        x, y, z = d[..., 0], d[..., 1], d[..., 2]
        return np.stack([1 + 0.5 * y + 0.3 * x * z, 1 + 0.2 * (3 * z * z - 1), 2 - 0.4 * x], -1)

    from conftest import sh_evaluate

    from envconv.resample.harmonics import irradiance_coefficients, project

    source = _source(low)
    irr = envconv.convert(source, "cube-faces", size=8, irradiance=True)
    texels = np.stack(np.meshgrid(np.arange(6), np.arange(8), np.arange(8), indexing="ij"),
                      -1).reshape(-1, 3)  # fmt: skip
    coeffs = irradiance_coefficients(project(source))
    truth = texel_mean(lambda d: sh_evaluate(coeffs, d) / math.pi, 8, texels, samples=8)
    got = _level_texels(irr.pixels, 8, texels)
    np.testing.assert_allclose(got, truth, rtol=3e-3)


def _pixel_sun(layout, n, row, col, value=1e5, sub=4):
    """A black map of ``layout`` at size n with one pixel of ``value``, and that pixel as point
    sources: directions (sub², 3) and solid angles (sub²) of its sub-pixels, from tests/naive."""
    width, height = naive.image_size(layout, n)
    pixels = np.zeros((height, width, 3), np.float32)
    pixels[row, col] = value
    o = (np.arange(sub) + 0.5) / sub
    u, v = np.meshgrid((col + o) / width, (row + o) / height)
    dirs, valid, dens = naive.uv_to_dir(layout, u, v)
    assert valid.all()
    aspect = naive.GRIDS[layout][3]
    omega = dens * (2 / (aspect * n)) * (2 / n) / sub**2
    return envconv.EnvMap(pixels, layout), dirs.reshape(-1, 3), omega.ravel()


def _sun_irradiance_errors(irr, suns, omega, value=1e5):
    """(energy ratio, worst texel error, RMS error; errors relative to the peak) of a 16 cube
    irradiance map against the cosine lobe of the point sources (suns, omega), integrated over
    each texel."""
    texels = np.stack(np.meshgrid(np.arange(6), np.arange(16), np.arange(16), indexing="ij"),
                      -1).reshape(-1, 3)  # fmt: skip

    def lit(d):
        return (value / math.pi * np.clip(d @ suns.T, 0, None) @ omega)[:, None] * np.ones(3)

    truth = texel_mean(lit, 16, texels, samples=8)
    got = _level_texels(irr.pixels, 16, texels)
    texel_omega = _level_texels(naive.pixel_solid_angles("cube-faces", 16, samples=8)[..., None],
                                16, texels)[:, 0]  # fmt: skip
    energy = (got[:, 0] * texel_omega).sum() / (truth[:, 0] * texel_omega).sum()
    peak = truth.max()
    return energy, np.abs(got - truth).max() / peak, np.sqrt(((got - truth) ** 2).mean()) / peak


@pytest.mark.parametrize(("row", "col", "rotate"), [
    (200, 333, None),   # an ordinary pixel
    (3, 1000, None),    # next to the pole
    (256, 128, None),   # on the horizon, where four cube faces meet at its longitude
    (150, 700, "30,-20,10"),
])  # fmt: skip
def test_irradiance_of_a_one_pixel_sun_keeps_its_energy_and_direction(row, col, rotate):
    """A 1024 × 512 lat-long is binned straight into the irradiance pyramid (ibl._bin_plan):
    the sun's energy is kept exactly and it shines from its own direction, so every texel is
    the cosine lobe of that pixel (integrated over the pixel and the texel)."""
    source, suns, omega = _pixel_sun("latlong", 512, row, col)
    assert envconv.resample.ibl._bin_plan(source, 64) == (1, math.pi / 512)
    irr = envconv.convert(source, "cube-faces", size=16, irradiance=True, rotate=rotate)
    if rotate is not None:
        from envconv.layouts.rotation import parse_rotation, rotation_matrix

        suns = suns @ rotation_matrix(*parse_rotation(rotate)).T  # source d lands at R d
    energy, worst, rms = _sun_irradiance_errors(irr, suns, omega)
    assert abs(energy - 1) < 0.005, energy
    assert worst <= 0.02
    assert rms <= 0.005


@pytest.mark.parametrize(("layout", "n", "row", "col"), [
    ("cube-faces", 128, 40, 300),   # 2 x 2 points a pixel
    ("cube-vcross", 256, 300, 400),  # a cross: the empty cells hold no points
    ("angular", 512, 100, 260),      # a disk: pixels cut by the rim take 16 x 16 points
])  # fmt: skip
def test_irradiance_of_a_one_pixel_sun_in_any_layout_keeps_its_energy(layout, n, row, col):
    """Other layouts are binned through their own geometry (ibl._bin_plan): the energy of one
    bright pixel is kept and shines from that pixel's own direction."""
    source, suns, omega = _pixel_sun(layout, n, row, col)
    assert envconv.resample.ibl._bin_plan(source, 64) is not None
    irr = envconv.convert(source, "cube-faces", size=16, irradiance=True)
    energy, worst, _ = _sun_irradiance_errors(irr, suns, omega)
    assert abs(energy - 1) < 0.005, energy
    assert worst <= 0.02


def test_binned_pyramid_is_the_same_on_one_and_many_threads():
    from envconv.layouts.geometry import kernel_geometry
    from envconv.resample import kernels

    source, _, _ = _pixel_sun("latlong", 512, 100, 200)
    source.pixels[...] += np.random.default_rng(3).random(source.pixels.shape, np.float32)
    rot = np.eye(3)
    previous = kernels.set_threads(1)
    try:
        one = kernels.ibl_pyramid_binned(source.pixels, rot, 64, sub=2)
        kernels.set_threads(3)
        many = kernels.ibl_pyramid_binned(source.pixels, rot, 64, sub=2)
    finally:
        kernels.set_threads(previous)
    assert one.tobytes() == many.tobytes()
    cross = np.random.default_rng(4).random((512, 384, 3), np.float32)
    geometry = kernel_geometry("cube-vcross", 128)
    previous = kernels.set_threads(1)
    try:
        one = kernels.ibl_pyramid_binned_any(cross, geometry, rot, 64, 2, 0.01)
        kernels.set_threads(3)
        many = kernels.ibl_pyramid_binned_any(cross, geometry, rot, 64, 2, 0.01)
    finally:
        kernels.set_threads(previous)
    assert one.tobytes() == many.tobytes()


def test_ggx_chain_in_ktx2_and_dds_reads_back_bit_for_bit(tmp_path):
    chain = envconv.convert(_source(analytic.radiance, 64), "cube-faces", size=16, mips="ggx")
    envconv.write(chain, tmp_path / "s.ktx2")
    info, data = read_container(tmp_path / "s.ktx2", tmp_path / "s.bin")
    assert info["keyValue"]["envconv:roughness"].rstrip("\0") == chain.metadata["envconv:roughness"]
    faces = [[np.concatenate([lv[:, f * (16 >> k) : (f + 1) * (16 >> k)],
                              np.ones(((16 >> k), (16 >> k), 1), np.float32)], 2)
              for f in range(6)] for k, lv in enumerate(chain.levels)]  # fmt: skip
    assert data == b"".join(face.tobytes() for level in faces for face in level)
    envconv.write(chain, tmp_path / "s.dds")
    _, data = read_container(tmp_path / "s.dds", tmp_path / "d.bin")
    assert data == b"".join(faces[k][f].tobytes() for f in range(6) for k in range(5))


def test_cli_ggx_and_irradiance(tmp_path):
    src = tmp_path / "sky.exr"
    envconv.write(_source(analytic.radiance, 32), src)
    out = tmp_path / "spec.dds"
    result = run_cli(["convert", src, out, "--to", "cube-faces", "--size", "8", "--mips", "ggx",
                      "--roughness", "unreal"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    result = run_cli(["convert", src, tmp_path / "irr.exr", "--to", "latlong", "--size", "8",
                      "--irradiance"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    irr = envconv.read(tmp_path / "irr.exr")
    assert irr.pixels.shape == (8, 16, 3) and irr.pixels.min() > 0
    result = run_cli(["convert", src, out, "--to", "cube-faces", "--mips", "ggx", "--roughness",
                      "0.1,x"])  # fmt: skip
    assert result.exit_code == 2 and "roughness" in result.stderr  # a bad option value: usage
    result = run_cli(["convert", src, out, "--to", "cube-faces", "--mips", "ggx:0"])
    assert result.exit_code == 2
