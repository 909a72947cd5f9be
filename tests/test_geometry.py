"""envconv.layouts.geometry against an independent reading of docs/geometry.md and numeric Jacobians."""

from __future__ import annotations

import math

import naive
import numpy as np
import pytest

from envconv.layouts import LAYOUTS, get_layout
from envconv.layouts.geometry import (
    horizon_pitch,
    pixel_directions,
    pixel_solid_angles,
    uv_to_dir,
)

NAMES = list(LAYOUTS)
DISKS = ["sphere", "angular", "paraboloid", "paraboloid-split", "fisheye"]
RECT = [name for name in NAMES if name not in DISKS]
# Tennisball's bands overlap (docs/geometry.md: about 6% of the sphere) and every pixel of both is
# valid, so its pixels cover two bands of (3π/2) · 2 sin(π/4) sr each rather than 4π.
TENNISBALL_AREA = 2 * (1.5 * math.pi) * (2 * math.sin(math.pi / 4))


def _cap(fov_deg):
    """Solid angle of a cone of full angle ``fov_deg`` (a fisheye's view)."""
    return 2 * math.pi * (1 - math.cos(math.radians(fov_deg) / 2))


def _pyramid(fov_h, fov_v):
    """Solid angle of a rectangular pyramid of full angles fov_h × fov_v (a perspective view):
    4 asin(sin(h/2) sin(v/2)), the spherical rectangle's area."""
    return 4 * math.asin(math.sin(math.radians(fov_h) / 2) * math.sin(math.radians(fov_v) / 2))


# What the layouts cover, when not the whole sphere: the partial ones with their default views.
AREA = {"tennisball": TENNISBALL_AREA, "fisheye": _cap(180), "perspective": _pyramid(90, 90)}


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("n", [3, 8])
def test_pixel_directions_match_the_conventions_formulas(name, n):
    dirs, flags = pixel_directions(name, n)
    width, height = get_layout(name).image_size(n)
    jj, ii = np.mgrid[0:height, 0:width]
    expected, valid, _ = naive.uv_to_dir(name, (ii + 0.5) / width, (jj + 0.5) / height)
    np.testing.assert_array_equal(flags == 2, valid)
    np.testing.assert_allclose(dirs[valid], expected[valid], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(dirs[valid], axis=-1), 1.0, atol=1e-12)


def _numeric_jacobian(name, n, u, v, h=1e-6):
    """|∂d/∂u × ∂d/∂v| by central differences of envconv's uv_to_dir (sr per unit uv area).

    Returns the Jacobian and a mask of points whose whole stencil lies in the valid region.
    """
    stencil = [(h, 0), (-h, 0), (0, h), (0, -h)]
    dirs, ok = [], np.ones(u.shape, bool)
    for du, dv in stencil:
        d, flags = uv_to_dir(name, u + du, v + dv, size=n)
        dirs.append(d)
        ok &= flags == 2
    d_du = (dirs[0] - dirs[1]) / (2 * h)
    d_dv = (dirs[2] - dirs[3]) / (2 * h)
    return np.linalg.norm(np.cross(d_du, d_dv), axis=-1), ok


@pytest.mark.parametrize("name", NAMES)
def test_pixel_solid_angles_match_numeric_jacobian(name):
    """Every family's density (per pixel, S×S midpoint) equals the finite-difference Jacobian."""
    n, s = 6, 3
    width, height = get_layout(name).image_size(n)
    u, v = naive.subsample_uv(name, n, s)
    jac, ok = _numeric_jacobian(name, n, u, v)
    _, flags = uv_to_dir(name, u, v, size=n)
    inside = flags == 2
    numeric = np.where(inside, jac, 0.0).sum(axis=(2, 3)) / (width * height * s * s)
    # Only pixels whose every valid sub-sample has a clean stencil (not straddling a rim).
    clean = np.all(ok | ~inside, axis=(2, 3))
    assert clean.mean() > 0.5
    got = pixel_solid_angles(name, n, samples=s)
    np.testing.assert_allclose(got[clean], numeric[clean], rtol=1e-6, atol=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_pixel_solid_angles_match_hand_derived_densities(name):
    """Same sub-samples, densities derived by hand in tests/naive.py (also checks naive)."""
    n, s = 8, 4
    np.testing.assert_allclose(
        pixel_solid_angles(name, n, samples=s), naive.pixel_solid_angles(name, n, s), rtol=1e-9
    )


@pytest.mark.parametrize("name", RECT)
def test_solid_angles_sum_to_the_sphere_rect(name):
    total = pixel_solid_angles(name, 16, samples=4).sum()
    assert total == pytest.approx(AREA.get(name, 4 * math.pi), rel=1e-3)


@pytest.mark.parametrize("name", DISKS)
def test_solid_angles_sum_to_the_sphere_disks(name):
    total = pixel_solid_angles(name, 32, samples=4).sum()
    assert total == pytest.approx(AREA.get(name, 4 * math.pi), rel=1e-2)


@pytest.mark.parametrize(
    "name, options, area",
    [
        ("fisheye", {"fov": 250, "yaw": 40, "pitch": -20}, _cap(250)),
        ("fisheye", {"fov": 360}, 4 * math.pi),
        ("fisheye", {"fov": 60, "roll": 30}, _cap(60)),
        ("perspective", {"fov": "100,60", "yaw": -70, "pitch": 35, "roll": 10}, _pyramid(100, 60)),
        ("perspective", {"fov": 150, "width": 30, "height": 12}, None),
    ],
)
def test_solid_angles_of_views_sum_to_what_they_cover(name, options, area):
    """The cone of a fisheye, the pyramid of a perspective view, whichever way it looks."""
    layout = get_layout(name).configure(**options)
    if area is None:  # one fov across a 30 x 12 image: the vertical one from the aspect
        v = 2 * math.degrees(math.atan(math.tan(math.radians(75)) * 12 / 30))
        area = _pyramid(150, v)
    n = layout.size_from_image(*layout.image_size(24))
    total = pixel_solid_angles(layout, n, samples=4).sum()
    assert total == pytest.approx(area, rel=1e-2 if layout.disk else 1e-3)


def test_solid_angles_of_latlong_rows_are_exact():
    """A lat-long row j spans lat bands: Ω = (2π/W) (sin lat_top − sin lat_bottom) per pixel."""
    n = 16
    omega = pixel_solid_angles("latlong", n, samples=8)
    edges = math.pi * (0.5 - np.arange(n + 1) / n)
    exact = (2 * math.pi / (2 * n)) * (np.sin(edges[:-1]) - np.sin(edges[1:]))
    np.testing.assert_allclose(omega, np.broadcast_to(exact[:, None], omega.shape), rtol=2e-3)


def test_horizon_pitch():
    """k in pitch = k/N along the horizon: π for lat-long; the mean of 2 cos(φ)^1.5 for cubes."""
    assert horizon_pitch("latlong") == pytest.approx(math.pi, rel=1e-6)
    phi = np.linspace(-math.pi / 4, math.pi / 4, 20001)
    cube = float(np.mean(2 * np.cos(phi) ** 1.5))  # √Ω of a face pixel at a = tan φ, times N
    for name in ("cube-vcross", "cube-hcross", "cube-exr", "cube-faces"):
        assert horizon_pitch(name) == pytest.approx(cube, rel=2e-3)


def test_uv_on_the_last_border_belongs_to_the_last_pixel():
    """u = 1 and v = 1 belong to the last pixel, so they still have a direction."""
    for name in ("latlong", "cube-hstrip", "tennisball"):
        dirs, flags = uv_to_dir(name, [1.0, 0.0], [1.0, 0.0], size=8)
        assert np.all(flags == 2)
        assert np.allclose(np.linalg.norm(dirs, axis=-1), 1.0)
