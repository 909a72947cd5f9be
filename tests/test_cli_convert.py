"""``envconv convert``: outputs re-opened through the library, and one-line errors."""

from __future__ import annotations

import os
import subprocess
import sys

import analytic
import naive
import numpy as np
import pytest
from conftest import file_state, rel_rms, run_cli, stderr_lines, write_plain

import envconv
from envconv.io import read_image
from envconv.layouts.geometry import pixel_solid_angles

ENVCONV = os.path.join(os.path.dirname(sys.executable), "envconv")


@pytest.fixture()
def sky(tmp_path):
    """A tagged 64 × 32 float lat-long EXR of the analytic environment."""
    path = tmp_path / "sky.exr"
    pixels = naive.pixel_average("latlong", 32, analytic.radiance, 4)
    envconv.write(envconv.EnvMap(pixels, "latlong"), path, bit_depth="float")
    return path


def test_convert_to_cross(tmp_path, sky):
    before = file_state(sky)
    out = tmp_path / "cross.exr"
    result = run_cli(["convert", sky, out, "--to", "cube-vcross", "--size", 16])
    assert result.exit_code == 0, result.stderr
    assert stderr_lines(result) == []
    assert file_state(sky) == before
    back = envconv.read(out)
    assert back.layout.name == "cube-vcross" and back.size == 16
    assert back.pixels.shape == (64, 48, 3) and back.channels == ("R", "G", "B")
    assert back.pixel_type == "float"
    assert read_image(out)[2]["envconv:layout"] == "cube-vcross"
    truth = naive.pixel_average("cube-vcross", 16, analytic.radiance, 8)
    mirrored = naive.pixel_average("cube-vcross", 16, analytic.mirrored(analytic.radiance), 4)
    omega = pixel_solid_angles("cube-vcross", 16)
    error = rel_rms(back.pixels, truth, omega)
    assert error < 0.05 and error < 0.1 * rel_rms(mirrored, truth, omega)


def test_convert_options_reach_the_library(tmp_path, sky):
    out = tmp_path / "rot.exr"
    result = run_cli(["convert", sky, out, "--to", "latlong", "--size", 32, "--rotate", "90,0,0",
                      "--filter", "bicubic", "--samples", 2, "--alpha"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    back = envconv.read(out)
    assert back.channels == ("R", "G", "B", "A")
    np.testing.assert_allclose(back.pixels[..., 3], 1.0)
    # Yaw 90 carries +Z to +X: the rotated map is the environment L(Ryᵀ d).
    ry_t = np.array([[0.0, 0, -1], [0, 1, 0], [1, 0, 0]])
    truth = naive.pixel_average("latlong", 32, lambda d: analytic.radiance(d @ ry_t.T), 8)
    unrotated = naive.pixel_average("latlong", 32, analytic.radiance, 4)
    omega = pixel_solid_angles("latlong", 32)
    error = rel_rms(back.pixels[..., :3], truth, omega)
    assert error < 0.1 * rel_rms(unrotated, truth, omega)


def test_convert_to_six_files(tmp_path, sky):
    template = os.fspath(tmp_path / "sky_{face}.exr")
    result = run_cli(["convert", sky, template, "--to", "cube-faces", "--size", 8])
    assert result.exit_code == 0, result.stderr
    names = ["px", "nx", "py", "ny", "pz", "nz"]
    assert sorted(os.listdir(tmp_path)) == sorted(["sky.exr"] + [f"sky_{f}.exr" for f in names])
    back = envconv.read(template)
    assert back.layout.name == "cube-faces" and back.size == 8


def test_convert_with_from_for_an_untagged_square(tmp_path, sky):
    disk = envconv.convert(envconv.read(sky), to="angular", size=16)
    write_plain(tmp_path / "probe.exr", disk.pixels)
    out = tmp_path / "ll.exr"
    result = run_cli(["convert", tmp_path / "probe.exr", out, "--from", "angular",
                      "--to", "latlong", "--size", 16])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert envconv.read(out).layout.name == "latlong"


def _garbage(tmp_path):
    path = tmp_path / "garbage.exr"
    path.write_bytes(b"\x00\x01 not an image at all " * 20)
    return path


def _square(tmp_path):
    path = tmp_path / "square.exr"
    write_plain(path, np.ones((16, 16, 3)))
    return path


# (id, input maker, extra arguments, output name)
ERROR_CASES = [
    ("missing-file", lambda t, sky: t / "nope.exr", ["--to", "latlong"], "out.exr"),
    ("unreadable-image", lambda t, sky: _garbage(t), ["--to", "latlong"], "out.exr"),
    ("unknown-to-layout", lambda t, sky: sky, ["--to", "cubemap-ish"], "out.exr"),
    ("unknown-from-layout", lambda t, sky: sky, ["--from", "dome", "--to", "latlong"], "out.exr"),
    ("ambiguous-aspect", lambda t, sky: _square(t), ["--to", "latlong"], "out.exr"),
    ("size-zero", lambda t, sky: sky, ["--to", "latlong", "--size", "0"], "out.exr"),
    ("size-does-not-fit-from", lambda t, sky: sky, ["--from", "cube-vcross", "--to", "latlong"],
     "out.exr"),
    ("multi-file-without-face", lambda t, sky: sky, ["--to", "cube-faces"], "out.exr"),
    ("face-with-single-file-layout", lambda t, sky: sky, ["--to", "latlong"], "out_{face}.exr"),
    ("unknown-output-extension", lambda t, sky: sky, ["--to", "latlong"], "out.xyz"),
]  # fmt: skip


@pytest.mark.parametrize("make_input, extra, out_name", [c[1:] for c in ERROR_CASES],
                         ids=[c[0] for c in ERROR_CASES])  # fmt: skip
def test_errors_are_one_line_with_no_output(tmp_path, sky, make_input, extra, out_name):
    source = make_input(tmp_path, sky)
    listing = sorted(os.listdir(tmp_path))
    result = run_cli(["convert", source, tmp_path / out_name, *extra])
    assert result.exit_code != 0
    lines = stderr_lines(result)
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.output and "Traceback" not in result.stderr
    assert sorted(os.listdir(tmp_path)) == listing  # no output, no temporary file


def test_real_process_error_and_success(tmp_path, sky):
    """The installed console script: exit status, stderr and files, as a user sees them."""
    missing = subprocess.run(
        [ENVCONV, "convert", tmp_path / "nope.exr", tmp_path / "o.exr", "--to", "latlong"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert missing.returncode != 0
    assert len([ln for ln in missing.stderr.splitlines() if ln.strip()]) == 1, missing.stderr
    assert "Traceback" not in missing.stderr
    assert not (tmp_path / "o.exr").exists()
    ok = subprocess.run(
        [ENVCONV, "convert", sky, tmp_path / "o.exr", "--to", "sphere", "--size", "16"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert ok.returncode == 0, ok.stderr
    assert envconv.read(tmp_path / "o.exr").layout.name == "sphere"


def test_threads_option_gives_the_same_file(tmp_path, sky):
    """--threads 1 and --threads 3 resample alike, byte for byte; --threads 0 is a usage error.
    A command run in this process leaves the process's thread count as it found it (it stayed
    3, and a later memory estimate in the same test process counted a third thread's scratch)."""
    from envconv.resample import kernels

    before = kernels.get_threads()
    outs = []
    for threads in (1, 3):
        out = tmp_path / f"t{threads}.exr"
        result = run_cli(["--threads", threads, "convert", sky, out, "--to", "angular",
                          "--size", 24, "--samples", 3, "--alpha"])  # fmt: skip
        assert result.exit_code == 0, result.stderr
        outs.append(envconv.read(out).pixels)
    assert outs[0].tobytes() == outs[1].tobytes()
    assert kernels.get_threads() == before
    bad = run_cli(["--threads", 0, "convert", sky, tmp_path / "x.exr", "--to", "angular"])
    assert bad.exit_code == 2 and len(stderr_lines(bad)) == 1


def test_convert_never_writes_onto_its_input(tmp_path, sky):
    """The output path is the input, or a link to it: one line, a non-zero status, the input
    untouched (the same bytes and mtime)."""
    before = file_state(sky)
    link = tmp_path / "link.exr"
    os.symlink(sky, link)
    for target in (sky, link):
        result = run_cli(["convert", sky, target, "--to", "cube-vcross", "--size", 8])
        assert result.exit_code != 0
        lines = stderr_lines(result)
        assert len(lines) == 1 and "never writes onto its input" in lines[0], lines
        assert file_state(sky) == before


@pytest.mark.parametrize("command", [["convert"], ["resample"]])
def test_help_states_the_default_size_rule_with_numbers_the_code_gives(command):
    """--help of convert and of the chain's resample states the default --size rule, and its
    worked numbers are what envconv.resample.options.default_size computes."""
    import re

    from envconv.resample.options import default_size

    text = " ".join(run_cli([*command, "--help"]).stdout.split())
    assert "pitch along the horizon" in text and "power of two" in text
    cube, latlong, chain = (int(n) for n in re.search(
        r"gives cube faces of (\d+), a lat-long of (\d+)\).*?\(\d+ becomes (\d+)\)", text).groups())  # fmt: skip
    source = envconv.EnvMap(np.zeros((1024, 2048, 3), np.float32), "latlong")
    assert default_size(source, "cube-vcross") == cube
    assert default_size(source, "latlong") == latlong
    assert default_size(source, "cube-vcross", mips=True) == chain


def test_convert_a_guarded_view_with_the_area_filter(tmp_path, sky):
    """``--filter area`` with ``--guard`` around a perspective view exits 0 (it exited 2): the
    file re-opens as the guarded view, its valid pixels the ringless map's and its ring alpha
    0; so does a fisheye whose ring reaches the point behind the view (that ring is
    point-sampled around the view's exact pixels)."""
    out, plain = tmp_path / "view.exr", tmp_path / "plain.exr"
    view = ["--to", "perspective", "--size", 16, "--pitch", -30, "--alpha"]
    result = run_cli(["convert", sky, out, *view, "--guard", 2, "--filter", "area"])
    assert result.exit_code == 0, result.stderr
    assert run_cli(["convert", sky, plain, *view]).exit_code == 0
    back, ringless = envconv.read(out), envconv.read(plain)
    assert back.guard == 2 and back.pixels.shape == (20, 20, 4)
    np.testing.assert_array_equal(back.pixels[2:18, 2:18], ringless.pixels)
    ring = np.ones((20, 20), bool)
    ring[2:18, 2:18] = False
    assert np.all(back.pixels[ring][:, 3] == 0) and np.all(back.pixels[ring][:, :3] > 0)
    folded = run_cli(["convert", sky, tmp_path / "fish.exr", "--to", "fisheye", "--fov", 300,
                      "--size", 16, "--guard", 4, "--filter", "area"])  # fmt: skip
    assert folded.exit_code == 0, folded.stderr
    assert envconv.read(tmp_path / "fish.exr").pixels.shape[:2] == (24, 24)
