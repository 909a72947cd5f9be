"""The fisheye against ffmpeg's v360 ``fisheye`` and against its own definition.

- ffmpeg 5.1 makes the same picture from the same lat-long, with its default field of view and
  with another one aimed by yaw, pitch and roll (so envconv's angles are ffmpeg's), corners
  included (``--guard fill``: ffmpeg continues the formula past the rim); the comparison tells
  it from a half-pixel shift, a mirrored picture and a turned one (tests/ffmpeg_peer.py).
- The angle from the axis grows linearly with the radius, fov/2 at the rim.
- As a source, a fisheye of less than 360° leaves the rest of the sphere a hole.
- The options flow through the command line, a chain and a graph file alike, are recorded in
  the file and read back; a bad value exits 2 with one line.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import run_cli, stderr_lines
from ffmpeg_peer import discriminates, pattern, pattern_latlong, v360

import envconv
from envconv.layouts import get_layout
from envconv.layouts.geometry import dir_to_uv, uv_to_dir

N = 32


@pytest.fixture(scope="module")
def source(tmp_path_factory):
    return pattern_latlong(tmp_path_factory.mktemp("fisheye"))


def _pattern_at(layout, n: int, du: float = 0.0) -> np.ndarray:
    """The pattern at every pixel centre of a fisheye (continued past the rim), moved by du
    pixels to the right."""
    jj, ii = np.mgrid[0:n, 0:n]
    dirs, _ = uv_to_dir(layout, (ii + 0.5 + du) / n, (jj + 0.5) / n, size=n, fill=True)
    return pattern(dirs)


@pytest.mark.parametrize(
    "ours, theirs",
    [
        ({}, ""),
        ({"fov": 200, "yaw": 30, "pitch": 20, "roll": 25}, ":h_fov=200:v_fov=200:yaw=30:pitch=20:roll=25"),
    ],
)  # fmt: skip
def test_fisheye_is_ffmpegs_picture(source, tmp_path, ours, theirs):
    path, sky = source
    peer = v360(path, tmp_path / "fisheye.png", f"e:fisheye:w={N}:h={N}{theirs}")
    # ffmpeg reads one bilinear tap at each pixel centre: so does envconv's point kernel (the
    # area filter, the default since a view's ring takes it too, is each pixel's mean).
    out = envconv.convert(sky, to="fisheye", size=N, samples=1, guard="fill", filter="bilinear",
                          **ours)  # fmt: skip
    layout = out.layout
    truth = _pattern_at(layout, N)
    wrong = {
        "half a pixel to the right": _pattern_at(layout, N, du=0.5),
        "mirrored": truth[:, ::-1],
        "turned a quarter": np.rot90(truth),
    }
    if ours:
        rolled = layout.configure(roll=-ours["roll"])
        wrong["rolled the other way"] = _pattern_at(rolled, N)
    near, _ = discriminates(out.pixels, peer, wrong)
    assert near < 1e-3


@pytest.mark.parametrize("fov", [180, 200, 90, 360])
def test_angle_from_the_axis_grows_linearly_with_the_radius(fov):
    layout = get_layout("fisheye").configure(fov=fov)
    radius = np.linspace(0.0, 1.0, 11)
    dirs, flags = uv_to_dir(layout, 0.5 + radius / 2, np.full_like(radius, 0.5), size=64)
    assert np.all(flags[:-1] == 2)
    angle = np.arccos(np.clip(dirs[:, 2], -1, 1))
    np.testing.assert_allclose(angle, np.radians(fov) / 2 * radius, atol=1e-9)
    assert np.all(dirs[1:, 0] <= 1e-12)  # image right is -X: unmirrored from inside


def test_partial_fisheye_source_leaves_holes():
    """A 120° fisheye of a constant sky, back to a lat-long: 1 inside the 60° cone about +Z,
    a hole (0, alpha 0) outside, and alpha its covered part across the edge."""
    sky = envconv.EnvMap(np.ones((64, 128, 3), np.float32), "latlong")
    fish = envconv.convert(sky, to="fisheye", size=64, fov=120)
    assert fish.layout.partial
    back = envconv.convert(fish, to="latlong", size=64, alpha=True)
    dirs, _ = uv_to_dir("latlong", *np.meshgrid((np.arange(128) + 0.5) / 128,
                                               (np.arange(64) + 0.5) / 64), size=64)  # fmt: skip
    off_axis = np.degrees(np.arccos(np.clip(dirs[..., 2], -1, 1)))
    inside, outside = off_axis < 55, off_axis > 65
    alpha = back.pixels[..., 3]
    np.testing.assert_allclose(alpha[inside], 1.0, atol=1e-6)
    np.testing.assert_allclose(back.pixels[inside][:, :3], 1.0, atol=2e-3)
    assert np.all(alpha[outside] == 0) and np.all(back.pixels[outside][:, :3] == 0)
    edge = ~inside & ~outside
    assert np.all(alpha[edge] >= 0) and np.all(alpha[edge] <= 1) and 0 < alpha[edge].mean() < 1
    # where colour is kept it is the mean of the covered samples: the sky's 1, not darker
    kept = edge & (alpha > 0.05)
    np.testing.assert_allclose(back.pixels[kept][:, :3], 1.0, atol=2e-3)


def test_view_options_flow_through_every_entry_point_and_read_back(tmp_path):
    sky = envconv.EnvMap(np.random.default_rng(1).random((32, 64, 3), np.float32), "latlong")
    envconv.io.write(sky, tmp_path / "sky.exr")
    options = ["--fov", "210", "--yaw", "-40", "--pitch", "15", "--roll", "5"]
    expected = envconv.convert(sky, to="fisheye", size=16, fov=210, yaw=-40, pitch=15, roll=5)
    cli = run_cli(["convert", tmp_path / "sky.exr", tmp_path / "cli.exr", "--to", "fisheye",
                   "--size", "16", *options])  # fmt: skip
    chain = run_cli(["read", tmp_path / "sky.exr", "resample", "--to", "fisheye", "--size", "16",
                     *options, "write", tmp_path / "chain.exr"])  # fmt: skip
    graph = {"steps": [{"step": "read", "path": "sky.exr"},
                       {"step": "resample", "to": "fisheye", "size": 16, "fov": 210, "yaw": -40,
                        "pitch": 15, "roll": 5},
                       {"step": "write", "path": "graph.exr"}]}  # fmt: skip
    (tmp_path / "g.json").write_text(json.dumps(graph))
    from_graph = run_cli(["run", tmp_path / "g.json"])
    for result, name in ((cli, "cli"), (chain, "chain"), (from_graph, "graph")):
        assert result.exit_code == 0, (name, result.stderr)
        back = envconv.io.read(tmp_path / f"{name}.exr")
        assert back.layout == expected.layout, name
        np.testing.assert_allclose(back.pixels, expected.pixels, atol=1e-3)
    # Read back, the view looks where the options say: 40° left of +Z (towards +X), 15° up.
    yaw, pitch = math.radians(40), math.radians(15)
    axis = [[math.sin(yaw) * math.cos(pitch), math.sin(pitch), math.cos(yaw) * math.cos(pitch)]]
    u, v = dir_to_uv(envconv.io.read(tmp_path / "cli.exr").layout, axis, size=16)
    assert (float(u[0]), float(v[0])) == pytest.approx((0.5, 0.5), abs=1e-9)


@pytest.mark.parametrize(
    "args, words",
    [
        (["--fov", "0"], "--fov"),
        (["--fov", "361"], "--fov"),
        (["--fov", "90,60"], "--fov"),
        (["--fov", "wide"], "--fov"),
        (["--yaw", "nan"], "--yaw"),
        (["--size", "32x16"], "fisheye"),
    ],
)
def test_bad_view_options_exit_2_with_one_line(tmp_path, args, words):
    sky = envconv.EnvMap(np.ones((8, 16, 3), np.float32), "latlong")
    envconv.io.write(sky, tmp_path / "sky.exr")
    result = run_cli(["convert", tmp_path / "sky.exr", tmp_path / "f.exr", "--to", "fisheye",
                      *args])  # fmt: skip
    assert result.exit_code == 2
    lines = stderr_lines(result)
    assert len(lines) == 1 and words in lines[0], lines
    assert not (tmp_path / "f.exr").exists()
