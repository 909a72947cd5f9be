"""The perspective view against py360convert's ``e2p`` and against its own definition.

- py360convert 1.0.4's perspective view (re-expressed in tests/py360_port.py; checked against
  py360convert itself where it is installed) of the same lat-long is envconv's, for any field
  of view, yaw, pitch and roll, once its fields of view (outermost pixel centres) are given as
  envconv's (image edges); the comparison tells it from a half-pixel shift, a mirrored or a
  turned picture, and from py360convert's fov taken as envconv's. ffmpeg v360's ``flat`` is
  the same view too (tests/ffmpeg_peer.py).
- The field of view spans the image edge to edge; straight lines stay straight.
- As a source it covers its frustum only: the rest of the sphere is a hole.
- W x H, --fov H[,V], --yaw, --pitch and --roll flow through the command line; a bad value exits
  2 with one line, and layouts that take no view refuse the options.
"""

from __future__ import annotations

import math

import numpy as np
import py360_port
import pytest
from conftest import run_cli, stderr_lines
from ffmpeg_peer import discriminates, pattern, pattern_latlong, rms, v360

import envconv
from envconv.layouts import get_layout
from envconv.layouts.geometry import dir_to_uv, pixel_directions, uv_to_dir

W, H = 48, 36


@pytest.fixture(scope="module")
def sky():
    dirs, _ = pixel_directions("latlong", 512)
    return envconv.EnvMap(pattern(dirs).astype(np.float32), "latlong")


def _py360_fov(fov: float, pixels: int) -> float:
    """py360convert's fov_deg (outermost pixel centres) for envconv's ``fov`` (image edges)."""
    return math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * (pixels - 1) / pixels))


def _pattern_at(layout, du: float = 0.0) -> np.ndarray:
    jj, ii = np.mgrid[0:H, 0:W]
    dirs, _ = uv_to_dir(layout, (ii + 0.5 + du) / W, (jj + 0.5) / H, size=H, fill=True)
    return pattern(dirs)


VIEWS = [  # envconv's fov (H, V), yaw, pitch, roll
    ((90, 70), 0, 0, 0),
    ((100, 60), 30, -20, 25),
    ((80, 80), -120, 40, -30),
    ((150, 120), 170, -75, 90),
]


@pytest.mark.parametrize("fov, yaw, pitch, roll", VIEWS)
def test_perspective_is_py360converts_view(sky, fov, yaw, pitch, roll):
    out = envconv.convert(
        sky,
        to="perspective",
        size=f"{W}x{H}",
        fov=f"{fov[0]},{fov[1]}",
        yaw=yaw,
        pitch=pitch,
        roll=roll,
        samples=1,
        filter="bilinear",
    )  # fmt: skip (py360convert reads one bilinear tap)
    assert out.pixels.shape == (H, W, 3)
    source = sky.pixels.astype(np.float64)
    peer = py360_port.e2p(source, (_py360_fov(fov[0], W), _py360_fov(fov[1], H)), yaw, pitch,
                          (H, W), roll)  # fmt: skip
    truth = _pattern_at(out.layout)
    wrong = {
        "half a pixel to the right": _pattern_at(out.layout, du=0.5),
        "mirrored": truth[:, ::-1],
        "turned half a turn": truth[::-1, ::-1],
        "py360convert's fov as envconv's": py360_port.e2p(source, fov, yaw, pitch, (H, W), roll),
    }
    near, _ = discriminates(out.pixels, peer, wrong, factor=20)
    assert near < 2e-5


@pytest.fixture(scope="module")
def sky_png(tmp_path_factory):
    return pattern_latlong(tmp_path_factory.mktemp("flat"))


@pytest.mark.parametrize("fov, yaw, pitch, roll", VIEWS[:2])
def test_perspective_is_ffmpegs_flat_view(tmp_path, sky_png, fov, yaw, pitch, roll):
    """ffmpeg v360's ``flat`` is the same pinhole view, its fields of view edge to edge as
    envconv's, its angles envconv's."""
    path, sky16 = sky_png
    peer = v360(path, tmp_path / "flat.png", f"e:flat:w={W}:h={H}:h_fov={fov[0]}:v_fov={fov[1]}"
                f":yaw={yaw}:pitch={pitch}:roll={roll}")  # fmt: skip
    out = envconv.convert(sky16, to="perspective", size=f"{W}x{H}", fov=f"{fov[0]},{fov[1]}",
                          yaw=yaw, pitch=pitch, roll=roll, samples=1)  # fmt: skip
    truth = _pattern_at(out.layout)
    wrong = {"half a pixel to the right": _pattern_at(out.layout, du=0.5),
             "mirrored": truth[:, ::-1], "turned half a turn": truth[::-1, ::-1]}  # fmt: skip
    near, _ = discriminates(out.pixels, peer, wrong)
    assert near < 1e-3


@pytest.mark.parametrize("fov, yaw, pitch, roll", VIEWS)
def test_the_port_is_py360convert(fov, yaw, pitch, roll):
    py360convert = pytest.importorskip("py360convert", reason="install the test extra")
    image = np.random.default_rng(5).random((64, 128, 3))
    expected = py360convert.e2p(image, fov, yaw, pitch, (H, W), roll, mode="bilinear")
    np.testing.assert_allclose(py360_port.e2p(image, fov, yaw, pitch, (H, W), roll), expected,
                               atol=1e-5)  # fmt: skip


def test_field_of_view_spans_the_image_edge_to_edge():
    layout = get_layout("perspective").configure(fov="100,60", width=W, height=H)
    edges = [(0.0, 0.5), (1.0, 0.5), (0.5, 0.0), (0.5, 1.0)]
    dirs, flags = uv_to_dir(layout, *np.array(edges).T, size=H)
    assert np.all(flags == 2)
    off_axis = np.degrees(np.arccos(dirs[:, 2]))
    np.testing.assert_allclose(off_axis, [50, 50, 30, 30], atol=1e-6)
    np.testing.assert_allclose(np.sign(dirs[:, :2]), [[1, 0], [-1, 0], [0, 1], [0, -1]])
    # one fov and W x H: the vertical one follows with square pixels
    square = get_layout("perspective").configure(fov=90, width=W, height=H)
    top, _ = uv_to_dir(square, [0.5], [0.0], size=H)
    assert math.tan(math.acos(top[0, 2])) == pytest.approx(H / W)


def test_straight_lines_stay_straight():
    """Points of a great circle (here the tilted plane y = 0.3 x + 0.2 z through the centre)
    land on one straight line of the image."""
    layout = get_layout("perspective").configure(fov=120, yaw=20, pitch=10, roll=5)
    t = np.linspace(-0.5, 0.5, 9)
    dirs = np.stack([np.sin(t), 0.3 * np.sin(t) + 0.2 * np.cos(t), np.cos(t)], -1)
    u, v = dir_to_uv(layout, dirs / np.linalg.norm(dirs, axis=-1, keepdims=True), size=64)
    slope, offset = np.polyfit(u, v, 1)
    np.testing.assert_allclose(v, slope * u + offset, atol=1e-9)


def test_perspective_source_covers_its_frustum_only():
    """A 90 x 90 view of a constant sky, back to a lat-long: 1 where |x|, |y| < z, a hole
    (0, alpha 0) where the view does not look."""
    sky = envconv.EnvMap(np.ones((64, 128, 3), np.float32), "latlong")
    view = envconv.convert(sky, to="perspective", size=64, fov=90)
    back = envconv.convert(view, to="latlong", size=64, alpha=True)
    dirs, _ = pixel_directions("latlong", 64)
    ratio = np.max(np.abs(dirs[..., :2]), axis=-1) / np.maximum(dirs[..., 2], 1e-9)
    inside, outside = (ratio < 0.9) & (dirs[..., 2] > 0), (ratio > 1.1) | (dirs[..., 2] <= 0)
    alpha = back.pixels[..., 3]
    np.testing.assert_allclose(alpha[inside], 1.0, atol=1e-6)
    np.testing.assert_allclose(back.pixels[inside][:, :3], 1.0, atol=1e-4)
    assert np.all(alpha[outside] == 0) and np.all(back.pixels[outside][:, :3] == 0)


def test_command_line_view_and_size(tmp_path, sky):
    envconv.io.write(sky, tmp_path / "sky.exr")
    result = run_cli(["convert", tmp_path / "sky.exr", tmp_path / "view.png", "--to",
                      "perspective", "--size", "64x48", "--fov", "100", "--yaw", "30",
                      "--pitch", "-10", "--roll", "5"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    back = envconv.io.read(tmp_path / "view.png")
    assert back.pixels.shape == (48, 64, 3) and back.layout.name == "perspective"
    assert back.layout.view_options == {"fov": 100.0, "yaw": 30.0, "pitch": -10.0, "roll": 5.0}
    expected = envconv.convert(sky, to="perspective", size="64x48", fov=100, yaw=30,
                               pitch=-10, roll=5)  # fmt: skip
    assert back.layout == expected.layout
    # without W x H: --size N is the height, the width follows the fields of view
    result = run_cli(["convert", tmp_path / "sky.exr", tmp_path / "wide.exr", "--to",
                      "perspective", "--size", "40", "--fov", "120,60"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    wide = envconv.io.read(tmp_path / "wide.exr")
    assert wide.pixels.shape[0] == 40
    assert wide.pixels.shape[1] == round(
        40 * math.tan(math.radians(60)) / math.tan(math.radians(30))
    )
    assert (
        rms(wide.pixels, envconv.convert(sky, to="perspective", size=40, fov="120,60").pixels)
        < 1e-3
    )


@pytest.mark.parametrize(
    "args, words",
    [
        (["--to", "perspective", "--fov", "180"], "--fov"),
        (["--to", "perspective", "--fov", "90,0"], "--fov"),
        (["--to", "perspective", "--fov", "90,60,30"], "--fov"),
        (["--to", "perspective", "--pitch", "inf"], "--pitch"),
        (["--to", "perspective", "--size", "64x"], "size"),
        (["--to", "perspective", "--size", "0x48"], "size"),
        (["--to", "latlong", "--yaw", "10"], "--yaw"),
        (["--to", "cube-faces", "--size", "64x48"], "cube-faces"),
    ],
)
def test_bad_options_exit_2_with_one_line(tmp_path, args, words):
    sky = envconv.EnvMap(np.ones((8, 16, 3), np.float32), "latlong")
    envconv.io.write(sky, tmp_path / "sky.exr")
    result = run_cli(["convert", tmp_path / "sky.exr", tmp_path / "out_{face}.exr", *args])
    assert result.exit_code == 2
    lines = stderr_lines(result)
    assert len(lines) == 1 and words in lines[0], lines
    assert not list(tmp_path.glob("out*"))
