"""Lat-long sample grids (layouts/grids.py) and their place in convert (resample/regrid.py).

Truths: the grids' positions as the module's table states them (and as Mitsuba's envmap.cpp
and OpenEXR's ImfEnvmap compute them: tests/test_mitsuba.py and tests/test_oiio_environment.py
check them against the programs), linear functions of (u, v), which linear interpolation keeps
exactly, and an analytic environment, a function of direction.
"""

from __future__ import annotations

import numpy as np
import pytest

import envconv
from envconv.errors import LayoutError, UsageError
from envconv.layouts.conventions import resolve_convention
from envconv.layouts.grids import GRID_TAG, from_centres, sample_positions, tagged_grid, to_centres
from envconv.resample.regrid import source_on_centres

H, W = 16, 32


def env(u, v):
    """A smooth environment of direction, at lat-long positions (u, v)."""
    lon, lat = 2 * np.pi * (0.5 - u), np.pi * (0.5 - v)
    x, y, z = np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)
    return np.stack([1 + 0.5 * x, 1 + 0.5 * y + 0.25 * y * y, 1 + 0.5 * z * x], axis=-1)


def on_grid(fn, grid, width=W, height=H):
    u, v = sample_positions(grid, width, height)
    uu, vv = np.meshgrid(u, v)
    return fn(uu, vv).astype(np.float32)


def test_sample_positions():
    u, v = sample_positions("centres", 4, 2)
    assert u.tolist() == [0.125, 0.375, 0.625, 0.875] and v.tolist() == [0.25, 0.75]
    u, v = sample_positions("edge-rows", 4, 3)
    assert u.tolist() == [0.125, 0.375, 0.625, 0.875] and v.tolist() == [0.0, 0.5, 1.0]
    u, v = sample_positions("edges", 5, 3)
    assert u.tolist() == [0.0, 0.25, 0.5, 0.75, 1.0] and v.tolist() == [0.0, 0.5, 1.0]
    with pytest.raises(UsageError, match="unknown lat-long grid"):
        sample_positions("corners", 4, 2)


@pytest.mark.parametrize("grid", ["edge-rows", "edges"])
def test_to_centres_is_exact_for_linear_functions(grid):
    def linear(u, v):
        return np.stack([3 * u - 2 * v, 1 + u + v], axis=-1)

    got = to_centres(on_grid(linear, grid), grid)
    np.testing.assert_allclose(got, on_grid(linear, "centres"), atol=1e-6)


@pytest.mark.parametrize("grid", ["edge-rows", "edges"])
def test_from_centres_is_exact_for_linear_functions_inside(grid):
    def linear(u, v):
        return (3 * u - 2 * v + 5)[..., None]

    got = from_centres(on_grid(linear, "centres"), grid)
    want = on_grid(linear, grid)
    inner_cols = slice(1, -1) if grid == "edges" else slice(None)  # the seam wraps
    np.testing.assert_allclose(got[1:-1, inner_cols], want[1:-1, inner_cols], atol=1e-5)


def test_a_pole_sample_is_the_mean_across_the_pole():
    px = np.random.default_rng(0).random((H, W, 2)).astype(np.float32)
    got = from_centres(px, "edge-rows")
    np.testing.assert_allclose(got[0], (px[0] + np.roll(px[0], W // 2, axis=0)) / 2, atol=1e-6)
    np.testing.assert_allclose(got[-1], (px[-1] + np.roll(px[-1], W // 2, axis=0)) / 2, atol=1e-6)
    np.testing.assert_allclose(
        got[H // 2 - 1 : H // 2 + 1].mean(), px[H // 2 - 1 : H // 2 + 1].mean(), atol=0.05
    )


@pytest.mark.parametrize("grid", ["edge-rows", "edges"])
def test_grids_carry_an_environment_to_the_interpolation_error(grid):
    """An environment of direction, moved both ways: within linear interpolation's h²/8 · f''
    (f'' ≤ 1 here, h = π/H), poles and seam included."""
    bound = (np.pi / H) ** 2 / 8 * 1.5
    there = from_centres(on_grid(env, "centres"), grid)
    assert np.abs(there - on_grid(env, grid)).max() < bound
    back = to_centres(on_grid(env, grid), grid)
    assert np.abs(back - on_grid(env, "centres")).max() < bound


def test_the_tag_and_the_input_convention():
    sky = envconv.EnvMap(on_grid(env, "edge-rows"), "latlong", metadata={GRID_TAG: "edge-rows"})
    assert tagged_grid(sky.metadata) == "edge-rows"
    moved = source_on_centres(sky, None)
    assert GRID_TAG not in moved.metadata
    assert np.abs(moved.pixels - on_grid(env, "centres")).max() < 0.01
    # An input convention wins over the tag: "envconv" says the samples are centred.
    kept = source_on_centres(sky, resolve_convention("envconv", "latlong"))
    np.testing.assert_array_equal(kept.pixels, sky.pixels)
    with pytest.raises(LayoutError, match="envconv:grid"):
        tagged_grid({GRID_TAG: "corners"})
    cube = envconv.EnvMap(
        np.ones((32, 24, 3), np.float32), "cube-vcross", metadata={GRID_TAG: "edges"}
    )
    with pytest.raises(UsageError, match="lat-long without a guard"):
        source_on_centres(cube, None)


def test_presets_name_their_grids():
    assert resolve_convention("mitsuba", "latlong").grid == "edge-rows"
    assert resolve_convention("mitsuba3", "latlong").grid == "edge-rows"
    assert resolve_convention("openexr-edges", "latlong").grid == "edges"
    assert resolve_convention("maketx", "latlong").grid == "edges"
    assert resolve_convention("openexr", "latlong").grid == "centres"
    assert not resolve_convention("mitsuba", "latlong").is_identity


@pytest.mark.parametrize("preset, grid", [("mitsuba", "edge-rows"), ("openexr-edges", "edges")])
def test_convert_writes_and_reads_a_grid(preset, grid):
    ours = envconv.EnvMap(on_grid(env, "centres"), "latlong")
    theirs = envconv.convert(ours, "latlong", size=H, out_convention=preset)
    assert theirs.metadata[GRID_TAG] == grid
    assert np.abs(theirs.pixels - on_grid(env, grid)).max() < 0.01
    tool = envconv.EnvMap(on_grid(env, grid), "latlong")  # untagged, as the tool writes it
    back = envconv.convert(tool, "latlong", size=H, in_convention=preset)
    assert np.abs(back.pixels - on_grid(env, "centres")).max() < 0.01
    plain = envconv.convert(tool, "latlong", size=H)
    assert np.abs(plain.pixels - on_grid(env, "centres")).max() > 0.02
