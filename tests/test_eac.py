"""The equi-angular cubemap against ffmpeg's v360 ``eac`` and against its own definition.

- ffmpeg 5.1 makes the same picture from the same lat-long (its fixed 2-pixel row padding cut
  out), and the comparison tells it from a half-pixel shift, a mirrored face and a turned face
  (tests/ffmpeg_peer.py).
- Along the horizon every pixel spans the same angle, across the three faces of the top row.
- Pixels' solid angles stay within a narrow band (the plain cube's vary five-fold).
- The command line writes it, tagged, and reads it back; a view option is refused with exit 2.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import run_cli, stderr_lines
from ffmpeg_peer import discriminates, pattern, pattern_latlong, v360

import envconv
from envconv.layouts.geometry import pixel_solid_angles, uv_to_dir

N = 24


@pytest.fixture(scope="module")
def source(tmp_path_factory):
    return pattern_latlong(tmp_path_factory.mktemp("eac"))


def _pattern_at(n: int, du: float = 0.0, dv: float = 0.0) -> np.ndarray:
    """The pattern at every pixel centre of an eac of size n, moved by (du, dv) pixels."""
    width, height = 3 * n, 2 * n
    jj, ii = np.mgrid[0:height, 0:width]
    dirs, _ = uv_to_dir("eac", (ii + 0.5 + du) / width, (jj + 0.5 + dv) / height, size=n)
    return pattern(dirs)


def _face(image: np.ndarray, face: int, n: int) -> tuple[slice, slice]:
    return slice(face // 3 * n, (face // 3 + 1) * n), slice(face % 3 * n, (face % 3 + 1) * n)


def test_eac_is_ffmpegs_picture(source, tmp_path):
    path, sky = source
    padded = v360(path, tmp_path / "eac.png", f"e:eac:w={3 * N + 4}:h={2 * N + 8}")
    # ffmpeg pads every row by 2 pixels on each side: its rows are N + 4 high, 3N + 4 wide.
    peer = np.concatenate([padded[r * (N + 4) + 2 : r * (N + 4) + 2 + N, 2 : 2 + 3 * N]
                           for r in (0, 1)])  # fmt: skip
    ours = envconv.convert(sky, to="eac", size=N, samples=1).pixels
    truth = _pattern_at(N)
    mirrored, turned = truth.copy(), truth.copy()
    mirrored[_face(truth, 1, N)] = truth[_face(truth, 1, N)][:, ::-1]  # the front face
    turned[_face(truth, 4, N)] = np.rot90(truth[_face(truth, 4, N)])  # the back face
    wrong = {
        "half a pixel to the right": _pattern_at(N, du=0.5),
        "half a pixel down": _pattern_at(N, dv=0.5),
        "front face mirrored": mirrored,
        "back face turned a quarter": turned,
    }
    near, _ = discriminates(peer, ours, wrong)
    assert near < 1e-3
    assert np.abs(peer - ours).max() < 4e-3


def test_horizon_pixels_are_equal_in_angle():
    """The top row's middle is the horizon from +X through +Z to -X: 3N pixels over 270°, each
    the same angle, across both seams (a plain cube's pixels shrink towards a face's edge)."""
    n = 9  # odd: the middle pixel row lies on the horizon
    u = (np.arange(3 * n) + 0.5) / (3 * n)
    dirs, _ = uv_to_dir("eac", u, np.full_like(u, 0.25), size=n)
    np.testing.assert_allclose(dirs[:, 1], 0.0, atol=1e-12)
    steps = np.arccos(np.clip(np.sum(dirs[1:] * dirs[:-1], axis=-1), -1, 1))
    np.testing.assert_allclose(steps, math.pi / 2 / n, rtol=1e-9)


def test_pixel_solid_angles_stay_near_their_mean():
    """(π/4)² (1 + a²)(1 + b²) / (1 + a² + b²)^1.5 runs from 0.83 (mid-edge) to 1.18 (centre)
    times its mean π/6."""
    eac = pixel_solid_angles("eac", 16, samples=4)
    cube = pixel_solid_angles("cube-faces", 16, samples=4)
    assert eac.sum() == pytest.approx(4 * math.pi, rel=1e-4)
    mean = 4 * math.pi / eac.size
    assert 0.83 < eac.min() / mean and eac.max() / mean < 1.18
    assert cube.max() / cube.min() > 4


def test_command_line_writes_and_reads_eac(tmp_path):
    sky = envconv.EnvMap(np.ones((16, 32, 3), np.float32), "latlong")
    envconv.io.write(sky, tmp_path / "sky.exr")
    result = run_cli(["convert", str(tmp_path / "sky.exr"), str(tmp_path / "eac.exr"),
                      "--to", "eac", "--size", "8"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    back = envconv.io.read(tmp_path / "eac.exr")
    assert back.layout.name == "eac" and back.size == 8 and back.pixels.shape == (16, 24, 3)
    np.testing.assert_allclose(back.pixels, 1.0, atol=1e-3)
    refused = run_cli(["convert", str(tmp_path / "sky.exr"), str(tmp_path / "x.exr"),
                       "--to", "eac", "--fov", "90"])  # fmt: skip
    assert refused.exit_code == 2
    assert len(stderr_lines(refused)) == 1 and "--fov" in refused.stderr
    assert not (tmp_path / "x.exr").exists()


def test_ffmpeg_preset_on_both_sides_changes_nothing(source):
    """ffmpeg's e and eac share its frame, so --in-convention ffmpeg with --out-convention
    ffmpeg is the picture without either (what ffmpeg itself makes); one alone turns it."""
    _, sky = source
    plain = envconv.convert(sky, to="eac", size=8, samples=1).pixels
    both = envconv.convert(sky, to="eac", size=8, samples=1, in_convention="ffmpeg",
                           out_convention="ffmpeg").pixels  # fmt: skip
    one = envconv.convert(sky, to="eac", size=8, samples=1, in_convention="ffmpeg").pixels
    np.testing.assert_allclose(both, plain, atol=1e-6)
    assert np.abs(one - plain).max() > 0.1
