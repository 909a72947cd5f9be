"""Every registered layout against docs/geometry.md: known directions (its table, read from the
page), round trips, size rule."""

from __future__ import annotations

import math

import naive
import numpy as np
import pytest
from geometry_doc import AXES, BOTTOM, OUTSIDE, RIM, TOP, known_directions
from hypothesis import assume, given
from hypothesis import strategies as st

from envconv.errors import LayoutError
from envconv.layouts import LAYOUTS, get_layout
from envconv.layouts.geometry import dir_to_uv, pixel_directions, uv_to_dir

ISSUE_LAYOUTS = [
    "latlong", "cube-vcross", "cube-hcross", "cube-hstrip", "cube-vstrip", "cube-exr",
    "cube-faces", "sphere", "angular", "paraboloid", "paraboloid-split", "tennisball",
    "octahedral", "equal-area", "eac", "fisheye", "perspective",
]  # fmt: skip

# The table "Where known directions land (u, v)", read from docs/geometry.md itself.
TABLE = known_directions()


def test_the_table_has_a_row_for_every_layout():
    assert sorted(TABLE) == sorted(LAYOUTS)


# W × H of the image in units of N (the mosaic for multi-file layouts), and the file size.
SIZE_RULE = {
    "latlong": (2, 1), "cube-vcross": (3, 4), "cube-hcross": (4, 3), "cube-hstrip": (6, 1),
    "cube-vstrip": (1, 6), "cube-exr": (1, 6), "cube-faces": (6, 1), "sphere": (1, 1),
    "angular": (1, 1), "paraboloid": (2, 1), "paraboloid-split": (2, 1), "tennisball": (3, 2),
    "octahedral": (1, 1), "equal-area": (1, 1), "eac": (3, 2), "fisheye": (1, 1),
    "perspective": (1, 1),
}  # fmt: skip
MULTI_FILE = {"cube-faces": 6, "paraboloid-split": 2}
DISKS = ("sphere", "angular", "paraboloid", "paraboloid-split")


def _covered(name, d) -> bool:
    """Whether layout ``name``'s default view sees direction ``d`` (always, unless partial)."""
    return name not in naive.PARTIAL or bool(naive.PARTIAL[name](d))


NUDGES = [(du, dv) for du in (0, -1, 1) for dv in (0, -1, 1)]


def _closest_dir(name, u, v, target, delta=1e-9):
    """Smallest |uv_to_dir(u, v) − target| over (u, v) and its neighbours ±delta.

    A point exactly on a cell border belongs to the cell right of or below it (docs/geometry.md),
    which may hold an unrelated face (e.g. cube-hstrip); the direction that dir_to_uv meant is
    then found an infinitesimal step into the neighbouring cell.
    """
    us = np.array([u + du * delta for du, _ in NUDGES])
    vs = np.array([v + dv * delta for _, dv in NUDGES])
    dirs, _ = uv_to_dir(name, us, vs, size=16)
    return float(np.min(np.linalg.norm(dirs - np.asarray(target), axis=-1)))


def test_registry_holds_every_layout_of_the_issue():
    assert sorted(LAYOUTS) == sorted(ISSUE_LAYOUTS)
    for name in ISSUE_LAYOUTS:
        assert get_layout(name).name == name
        assert LAYOUTS[name].description


def test_unknown_layout_raises_layout_error_with_suggestion():
    with pytest.raises(LayoutError, match="cube-vcross"):
        get_layout("cube-vcros")


@pytest.mark.parametrize("name", ISSUE_LAYOUTS)
@pytest.mark.parametrize("n", [16, 37])
def test_known_directions_land_where_the_table_says(name, n):
    dirs = np.array(list(AXES.values()))
    u, v = dir_to_uv(name, dirs, size=n)
    for k, (label, expected) in enumerate(zip(AXES, TABLE[name], strict=True)):
        got = (float(u[k]), float(v[k]))
        if expected == TOP:
            assert got[1] == pytest.approx(0.0, abs=1e-9), label
        elif expected == BOTTOM:
            assert got[1] == pytest.approx(1.0, abs=1e-9), label
        elif expected == RIM:
            radius = math.hypot(2 * got[0] - 1, 2 * got[1] - 1)
            assert radius == pytest.approx(1.0, abs=1e-4), label
        elif expected == OUTSIDE:  # sent to the edge of the image (its reach, without guard)
            assert not _covered(name, dirs[k]), label
            assert min(got[0], 1 - got[0], got[1], 1 - got[1]) < 1e-9, (label, got)
        elif isinstance(expected, list):
            assert any(np.allclose(got, e, atol=1e-4) for e in expected), (label, got)
        else:
            assert got == pytest.approx(expected, abs=1e-4), (label, got)


@pytest.mark.parametrize("name", ISSUE_LAYOUTS)
def test_table_positions_map_back_to_their_directions(name):
    for (label, d), expected in zip(AXES.items(), TABLE[name], strict=True):
        if not isinstance(expected, tuple):
            continue
        # The table rounds to 4 digits, so allow the direction error that rounding causes.
        assert _closest_dir(name, *expected, d, delta=1e-6) < 2e-3, label


def _unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v)


SPECIAL_DIRS = [_unit(d) for d in (
    (1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1),
    (1, 1, 0), (1, -1, 0), (-1, 0, 1), (0, 1, -1), (1, 1, 1), (-1, -1, -1), (1, -1, 1),
    (0.48, 0.6, 0.64), (math.sqrt(0.5), math.sqrt(0.5), 1e-17), (1e-12, 0, -1), (1e-12, 1, 0),
    (0.5, math.sqrt(0.5), 0.5), (-math.sqrt(0.5), 0.1, -0.7),
    (0.0, 1e-160, -1.0),  # |(x, y)|² is subnormal: needs hypot, not sqrt(x² + y²)
    (5e-324, 5e-324, -1.0),  # subnormal x, y: x / hypot(x, y) is 1 unless scaled up first
)]  # fmt: skip

random_dirs = st.tuples(
    *[st.floats(-1, 1, allow_nan=False, allow_infinity=False) for _ in range(3)]
).filter(lambda v: np.linalg.norm(v) > 1e-3)
directions = st.one_of(st.sampled_from(SPECIAL_DIRS), random_dirs.map(_unit))


@pytest.mark.parametrize("name", ISSUE_LAYOUTS)
@given(d=directions)
def test_dir_to_uv_to_dir_round_trip(name, d):
    if name in naive.PARTIAL:  # into the default view (|x|, |y| < z): no direction filtered out
        d = _unit((d[0], d[1], abs(d[2]) + 1.01 * (abs(d[0]) + abs(d[1]))))
        assert _covered(name, d)
    u, v = dir_to_uv(name, d, size=16)
    assert 0.0 <= u <= 1.0 and 0.0 <= v <= 1.0
    assert _closest_dir(name, float(u), float(v), d) < 1e-6


def _owned_uv_ok(name, uv_in, uv_out, dir_in):
    """uv → dir → uv gives the same point, except where a direction has two homes."""
    if np.allclose(uv_in, uv_out, atol=1e-7):
        return True
    # Tennisball bands overlap: a pixel of one band may hold a direction the band rule gives
    # to the other. Then the returned point must still show the same direction.
    return name == "tennisball" and _closest_dir(name, *uv_out, dir_in) < 1e-7


@pytest.mark.parametrize("name", ISSUE_LAYOUTS)
@pytest.mark.parametrize("n", [5, 8])
def test_pixel_centres_round_trip_uv_dir_uv(name, n):
    dirs, flags = pixel_directions(name, n)
    width, height = get_layout(name).image_size(n)
    jj, ii = np.mgrid[0:height, 0:width]
    centres = np.stack([(ii + 0.5) / width, (jj + 0.5) / height], -1)
    valid = flags == 2
    assert valid.any()
    u, v = dir_to_uv(name, dirs[valid], size=n)
    back = np.stack([u, v], -1)
    for uv_in, uv_out, d in zip(centres[valid], back, dirs[valid], strict=True):
        assert _owned_uv_ok(name, uv_in, uv_out, d), (uv_in, uv_out)


@pytest.mark.parametrize("name", ISSUE_LAYOUTS)
@given(u=st.floats(0.0005, 0.9995), v=st.floats(0.0005, 0.9995))
def test_valid_points_round_trip_uv_dir_uv(name, u, v):
    (d,), (flag,) = uv_to_dir(name, [u], [v], size=16)
    assume(flag == 2)
    # A point on a border between cells has a twin in the neighbouring cell (the cube's edges
    # and corners); dir_to_uv may return either, which test_dir_to_uv_to_dir_round_trip covers.
    _, cols, rows, _, _ = naive.GRIDS[name]
    for t in (u * cols, v * rows):
        assume(min(t % 1, 1 - t % 1) > 1e-6)
    if name in DISKS:  # the rim holds the singular direction -Z (sphere, angular)
        cols = 2 if name.startswith("paraboloid") else 1
        a = (u * cols % 1) * 2 - 1
        assume(math.hypot(a, 2 * v - 1) < 0.999)
    uu, vv = dir_to_uv(name, d, size=16)
    assert _owned_uv_ok(name, np.array([u, v]), np.array([float(uu), float(vv)]), d)


@pytest.mark.parametrize("name", ISSUE_LAYOUTS)
@pytest.mark.parametrize("n", [1, 5, 32])
def test_size_rule(name, n):
    layout = get_layout(name)
    kw, kh = SIZE_RULE[name]
    assert layout.image_size(n) == (kw * n, kh * n)
    assert layout.size_from_image(kw * n, kh * n) == n
    if name in MULTI_FILE:
        assert layout.multi_file and layout.n_faces == MULTI_FILE[name]
        assert layout.file_size(n) == (n, n)
    else:
        assert not layout.multi_file
        assert layout.file_size(n) == (kw * n, kh * n)


@pytest.mark.parametrize("name", ISSUE_LAYOUTS)
@pytest.mark.parametrize("n", [4, 9])
def test_wrong_sizes_raise_layout_error(name, n):
    layout = get_layout(name)
    width, height = layout.image_size(n)
    for bad in [(width + 1, height), (width, height + 1), (width, 2 * height), (0, 0)]:
        with pytest.raises(LayoutError):
            layout.size_from_image(*bad)


@pytest.mark.parametrize("name", ISSUE_LAYOUTS)
def test_empty_cells_and_outside_disks_hold_no_direction(name):
    """Pixels whose centres lie outside the valid region have flag 0 and no direction."""
    n = 8
    dirs, flags = pixel_directions(name, n)
    width, height = get_layout(name).image_size(n)
    jj, ii = np.mgrid[0:height, 0:width]
    _, valid, _ = naive.uv_to_dir(name, (ii + 0.5) / width, (jj + 0.5) / height)
    np.testing.assert_array_equal(flags == 2, valid)
    assert np.all(flags[~valid] == 0)
    assert np.all(dirs[~valid] == 0)
