"""Order-2 spherical harmonics (envconv.resample.harmonics, ``envconv sh``) against direct numeric projection
and the irradiance of known environments (Ramamoorthi & Hanrahan 2001)."""

from __future__ import annotations

import json
import math

import analytic
import naive
import numpy as np
import pytest
from conftest import run_cli, sh_evaluate

import envconv
from envconv.resample.harmonics import (
    irradiance_coefficients,
    irradiance_matrix,
    project,
    sh_basis,
)


def _direct(fn, n_lat=192, n_lon=384):
    """∫ fn Y_lm dω by Gauss–Legendre in y and the midpoint rule in longitude."""
    y, wy = np.polynomial.legendre.leggauss(n_lat)
    lon = (np.arange(n_lon) + 0.5) / n_lon * 2 * np.pi
    yy, ll = np.meshgrid(y, lon, indexing="ij")
    r = np.sqrt(1 - yy**2)
    d = np.stack([r * np.sin(ll), yy, r * np.cos(ll)], -1)
    w = wy[:, None] * (2 * np.pi / n_lon)
    return np.einsum("ijk,ijc,ij->kc", sh_basis(d), fn(d), w)


@pytest.mark.parametrize("layout,n", [("latlong", 64), ("cube-vcross", 32), ("tennisball", 40),
                                      ("sphere", 192), ("paraboloid", 64), ("angular", 96)])  # fmt: skip
def test_projection_matches_direct_numeric_projection(layout, n):
    for fn in (analytic.smooth_radiance, analytic.radiance):
        pixels = naive.pixel_average(layout, n, fn, samples=8).astype(np.float32)
        got = project(envconv.EnvMap(pixels, layout))
        truth = _direct(fn)
        assert (np.abs(got - truth).max(axis=0) / np.linalg.norm(truth, axis=0)).max() < 1e-3


def test_basis_is_orthonormal():
    np.testing.assert_allclose(_direct(lambda d: sh_basis(d)), np.eye(9), atol=1e-10)


def test_irradiance_of_known_environments():
    w = np.array([0.36, 0.48, 0.8])
    dirs = analytic.fibonacci_directions(200)
    # Constant c: E = π c. Linear a + b (d·w): E(n) = π a + (2π/3) b (n·w) (R&H: exact).
    sky = naive.pixel_average("latlong", 64, lambda d: 2.0 + 3.0 * (d @ w)[..., None], samples=8)
    coeffs = irradiance_coefficients(project(envconv.EnvMap(sky.astype(np.float32), "latlong")))
    truth = math.pi * 2.0 + 2 * math.pi / 3 * 3.0 * (dirs @ w)
    np.testing.assert_allclose(
        sh_evaluate(coeffs, dirs)[:, 0], truth, rtol=0, atol=1e-3 * truth.max()
    )
    # The quadratic form of R&H eq. 12 gives the same irradiance.
    m = irradiance_matrix(project(envconv.EnvMap(sky.astype(np.float32), "latlong")))[0]
    h = np.concatenate([dirs, np.ones((len(dirs), 1))], 1)
    np.testing.assert_allclose(
        np.einsum("ni,ij,nj->n", h, m, h), truth, rtol=0, atol=2e-3 * truth.max()
    )


def test_cube_frame_flips_the_terms_odd_in_x():
    sky = envconv.EnvMap(naive.pixel_average("latlong", 32, analytic.radiance, 4).astype(np.float32),
                         "latlong")  # fmt: skip
    world, cube = project(sky), project(sky, frame="cube")
    sign = np.array([1, 1, 1, -1, -1, 1, 1, -1, 1])[:, None]
    np.testing.assert_allclose(cube, sign * world, rtol=1e-9, atol=1e-12)


def test_cli_prints_json(tmp_path):
    src = tmp_path / "sky.exr"
    pixels = naive.pixel_average("latlong", 32, analytic.smooth_radiance, 4).astype(np.float32)
    envconv.write(envconv.EnvMap(pixels, "latlong"), src)
    result = run_cli(["sh", src])
    assert result.exit_code == 0, result.stderr
    record = json.loads(result.stdout)
    assert record["basis"]["order"][3] == "l=1,m=1" and record["channels"] == ["R", "G", "B"]
    got = np.array(record["radiance"]["coefficients"])
    np.testing.assert_allclose(
        got, _direct(analytic.smooth_radiance), rtol=0, atol=2e-3 * np.abs(got).max()
    )
    assert np.array(record["irradiance"]["matrix"]["M"]).shape == (3, 4, 4)
    missing = run_cli(["sh", tmp_path / "nope.exr"])
    assert missing.exit_code == 1 and len(missing.stderr.strip().splitlines()) == 1
