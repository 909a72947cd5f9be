"""The labelled test pattern: labels at the right axes, upright and unmirrored from inside."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import envconv
from envconv.cli.main import cli
from envconv.layouts.geometry import pixel_directions
from envconv.views.pattern import GLYPH_UNIT, pattern, render_pattern

# How the glyphs must read (written out here, independently of the module's font).
READS = {
    "+": ["     ", "  #  ", "  #  ", "#####", "  #  ", "  #  ", "     "],
    "-": ["     ", "     ", "     ", "#####", "     ", "     ", "     "],
    "X": ["#   #", "#   #", " # # ", "  #  ", " # # ", "#   #", "#   #"],
    "Y": ["#   #", "#   #", " # # ", "  #  ", "  #  ", "  #  ", "  #  "],
    "Z": ["#####", "    #", "   # ", "  #  ", " #   ", "#    ", "#####"],
}

# World direction of point (a, b) (a right, b down) of the cube face that looks at each axis:
# the GL table of docs/geometry.md, whose faces are unmirrored views from inside, with
# d = (-c_x, c_y, c_z).
FACE_VIEW = {
    "+X": lambda a, b: (1.0, -b, a),  # -X_c
    "-X": lambda a, b: (-1.0, -b, -a),  # +X_c
    "+Y": lambda a, b: (-a, 1.0, b),  # +Y_c
    "-Y": lambda a, b: (-a, -1.0, -b),  # -Y_c
    "+Z": lambda a, b: (-a, -b, 1.0),  # +Z_c
    "-Z": lambda a, b: (a, -b, -1.0),  # -Z_c
}
AXES = {
    "+X": (1, 0, 0),
    "-X": (-1, 0, 0),
    "+Y": (0, 1, 0),
    "-Y": (0, -1, 0),
    "+Z": (0, 0, 1),
    "-Z": (0, 0, -1),
}


def _expected_text(text):
    rows = ["".join(READS[ch][r] + " " for ch in text)[:-1] for r in range(7)]
    return np.array([[c == "#" for c in row] for row in rows])


@pytest.mark.parametrize("text", list(FACE_VIEW))
def test_label_reads_unmirrored_from_inside(text):
    """Sampled at the centres of the font cells on the cube face looking at the axis, the
    pattern spells the label exactly: white ink where the letters are, dark plate elsewhere."""
    expected = _expected_text(text)
    rows, cols = np.mgrid[0:7, 0 : expected.shape[1]]
    a = (cols + 0.5 - expected.shape[1] / 2) * GLYPH_UNIT
    b = (rows + 0.5 - 3.5) * GLYPH_UNIT
    d = np.stack(np.broadcast_arrays(*FACE_VIEW[text](a, b)), -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    colour = pattern(d)
    ink = np.all(colour == 1.0, axis=-1)
    plate = np.all(colour < 0.1, axis=-1)
    np.testing.assert_array_equal(ink, expected)
    np.testing.assert_array_equal(plate, ~expected)
    # The text is not mirror-symmetric, so a mirrored label could not pass.
    assert not np.array_equal(expected, expected[:, ::-1])


def test_ink_lands_near_its_axis_in_latlong():
    n = 96
    img = render_pattern("latlong", n, samples=2).pixels
    dirs, _ = pixel_directions("latlong", n)
    white = np.all(img > 0.97, axis=-1)
    assert white.sum() > 100
    near = {t: dirs[white] @ np.array(v, float) > np.cos(np.radians(30)) for t, v in AXES.items()}
    # Every white pixel belongs to a label, and each horizon label has ink centred on its axis.
    assert np.all(np.any(list(near.values()), axis=0))
    for text in ("+X", "-X", "+Z", "-Z"):
        centre = dirs[white][near[text]].mean(0)
        centre /= np.linalg.norm(centre)
        assert np.degrees(np.arccos(centre @ AXES[text])) < 4.0


def test_hemisphere_colours_differ():
    """Around each axis (outside its label) the colour tells the axis from its opposite."""
    rng = np.random.default_rng(3)
    for k in range(3):
        means = []
        for sign in (1.0, -1.0):
            axis = np.zeros(3)
            axis[k] = sign
            ring = rng.normal(size=(500, 3))
            ring -= np.outer(ring @ axis, axis)
            ring /= np.linalg.norm(ring, axis=1, keepdims=True)
            d = np.cos(np.radians(35)) * axis + np.sin(np.radians(35)) * ring
            means.append(pattern(d).mean(0))
        assert means[0][k] - means[1][k] > 0.3


@pytest.mark.parametrize("layout, n", [("cube-vcross", 12), ("sphere", 24), ("tennisball", 8)])
def test_render_matches_pattern_at_pixel_centres(layout, n):
    img = render_pattern(layout, n, samples=1, alpha=True)
    dirs, flags = pixel_directions(layout, n)
    valid = flags == 2
    np.testing.assert_allclose(img.pixels[..., :3][valid], pattern(dirs[valid]), atol=1e-6)
    assert np.all(img.pixels[~valid] == 0.0)
    np.testing.assert_array_equal(img.pixels[..., 3], valid.astype(np.float32))


def test_render_in_a_tool_convention():
    """Drawn for skylibs, the lat-long centre shows the -Z label (skylibs' forward)."""
    n = 32
    img = render_pattern("latlong", n, samples=1, convention="skylibs").pixels
    u = (np.arange(2 * n) + 0.5) / (2 * n)
    v = (np.arange(n) + 0.5) / n
    uu, vv = np.meshgrid(u, v)
    theta, phi = np.pi * (2 * uu - 1), np.pi * vv  # skylibs latlong2world
    d = np.stack([np.sin(phi) * np.sin(theta), np.cos(phi), -np.sin(phi) * np.cos(theta)], -1)
    np.testing.assert_allclose(img, pattern(d), atol=1e-5)


def test_cli_pattern(tmp_path):
    runner = CliRunner()
    out = tmp_path / "p.exr"
    result = runner.invoke(cli, ["pattern", str(out), "--to", "cube-hcross", "--size", "16"])
    assert result.exit_code == 0, result.output
    back = envconv.read(str(out))
    assert back.layout.name == "cube-hcross" and back.size == 16
    truth = render_pattern("cube-hcross", 16).pixels
    assert np.abs(back.pixels - truth).max() < 2e-3  # half float
    faces = tmp_path / "f_{face}.exr"
    args = [
        "pattern",
        str(faces),
        "--to",
        "cube-faces",
        "--size",
        "8",
        "--out-convention",
        "openexr",
    ]
    assert runner.invoke(cli, args).exit_code == 0
    assert (tmp_path / "f_px.exr").exists()
    bad = runner.invoke(cli, ["pattern", str(out), "--to", "cube-faces", "--size", "8"])
    assert bad.exit_code == 1 and "{face}" in bad.output
    bad = runner.invoke(cli, ["pattern", str(out), "--to", "sphere", "--out-convention", "unreal"])
    assert bad.exit_code == 1 and "applies to latlong" in bad.output
