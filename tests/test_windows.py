"""Display and data windows: files crafted with OIIO, read and converted as OpenEXR means them.

The truth is the display-window semantics itself, applied by hand to the pixels written: the
data window's pixels sit where their coordinates put them, the rest of the display window is a
hole (alpha 0), overscan is cut off. Converted maps are checked against conversions of
hole-free files and against solid-angle integrals.
"""

from __future__ import annotations

import os

import analytic
import naive
import numpy as np
import pytest
from conftest import run_cli, stderr_lines

import envconv
from envconv.io.files import place_in_display, read_file_header


def write_window(path, pixels, display, data, names="RGB", pixel_type="float"):
    """Write ``pixels`` (the data window's) with OIIO, windows given as (x, y, w, h)."""
    import OpenImageIO as oiio

    height, width, nch = pixels.shape
    assert (width, height) == data[2:]
    spec = oiio.ImageSpec(width, height, nch, getattr(oiio, pixel_type.upper()))
    spec.channelnames = tuple(names)
    spec.x, spec.y = data[:2]
    spec.full_x, spec.full_y, spec.full_width, spec.full_height = display
    out = oiio.ImageOutput.create(os.fspath(path))
    assert out.open(os.fspath(path), spec), out.geterror()
    assert out.write_image(np.ascontiguousarray(pixels, np.float32)), out.geterror()
    assert out.close()


@pytest.fixture(scope="module")
def sky():
    """An analytic lat-long, N = 32 (64 x 32), as pixel averages."""
    return naive.pixel_average("latlong", 32, analytic.radiance, 4).astype(np.float32)


def test_top_half_data_window_reads_as_the_display_window_with_a_hole(tmp_path, sky):
    """Display 64x32, data 64x16: a lat-long (not a 4:1 image that fits nothing) whose lower
    hemisphere is a hole: colour 0 and alpha 0 there, 1 above."""
    write_window(tmp_path / "top.exr", sky[:16], (0, 0, 64, 32), (0, 0, 64, 16))
    env = envconv.read(tmp_path / "top.exr")
    assert env.layout.name == "latlong" and env.size == 32
    assert env.channels == ("R", "G", "B", "A")
    np.testing.assert_array_equal(env.pixels[:16, :, :3], sky[:16])
    np.testing.assert_array_equal(env.pixels[16:], 0)
    np.testing.assert_array_equal(
        env.pixels[:, :, 3], np.repeat([1.0, 0.0], 16)[:, None] * np.ones(64)
    )
    np.testing.assert_array_equal(env.valid, env.pixels[:, :, 3])


def test_offset_data_window_equals_the_shifted_image_with_empty_columns(tmp_path, sky):
    """A full-size data window starting at x = 10 (display 0..63): the map is the data shifted
    right by 10 pixels, its first 10 columns empty; the data's last 10 columns are overscan.
    Converting it to the same grid gives exactly that map."""
    write_window(tmp_path / "offset.exr", sky, (0, 0, 64, 32), (10, 0, 64, 32))
    expected = np.zeros((32, 64, 4), np.float32)
    expected[:, 10:, :3] = sky[:, :54]
    expected[:, 10:, 3] = 1.0
    env = envconv.read(tmp_path / "offset.exr")
    np.testing.assert_array_equal(env.pixels, expected)
    result = run_cli(["convert", tmp_path / "offset.exr", tmp_path / "same.exr", "--to", "latlong",
                      "--size", "32", "--bit-depth", "float"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    np.testing.assert_array_equal(envconv.read(tmp_path / "same.exr").pixels, expected)


def test_offset_data_window_turns_the_environment_where_it_holds_data(tmp_path, sky):
    """Shifting a lat-long right by 10 of 64 columns turns its environment by -56.25° about +Y
    (content at u moves to u + 10/64; +Z is at u = 0.5, +X at 0.25, and --rotate turns the
    environment by the right-hand rule). Wherever the cross is wholly covered (alpha 1) it
    equals the rotated conversion of the unshifted file; where nothing is held it is empty."""
    write_window(tmp_path / "offset.exr", sky, (0, 0, 64, 32), (10, 0, 64, 32))
    write_window(tmp_path / "plain.exr", sky, (0, 0, 64, 32), (0, 0, 64, 32))
    common = ["--to", "cube-vcross", "--size", "16", "--bit-depth", "float", "--samples", "2"]
    assert run_cli(["convert", tmp_path / "offset.exr", tmp_path / "a.exr", *common]).exit_code == 0
    assert run_cli(["convert", tmp_path / "plain.exr", tmp_path / "b.exr", *common,
                    "--rotate", "-56.25,0,0"]).exit_code == 0  # fmt: skip
    shifted, turned = envconv.read(tmp_path / "a.exr"), envconv.read(tmp_path / "b.exr")
    alpha = shifted.pixels[:, :, 3]
    full = alpha == 1.0
    assert full.mean() > 0.35 and (alpha == 0).any()  # the cross itself is half the image
    np.testing.assert_allclose(
        shifted.pixels[full][:, :3], turned.pixels[full][:, :3], rtol=1e-5, atol=1e-6
    )
    np.testing.assert_array_equal(shifted.pixels[alpha == 0], 0)


@pytest.mark.parametrize("flag", [[], ["--alpha"]])
def test_a_hole_converts_as_a_hole_not_as_black_sky(tmp_path, sky, flag):
    """The top 13 of 32 rows converted to a cross: alpha covers the sky above latitude
    90° - 13/32 · 180°, a solid-angle fraction (1 - sin φ)/2 of the sphere, with or without
    --alpha; pixels wholly held equal the conversion of the whole map. A constant sky stays
    constant wherever anything is held: a pixel on the hole's rim keeps the colour it holds
    rather than fading to black with its alpha."""
    common = ["--to", "cube-vcross", "--size", "16", "--bit-depth", "float", *flag]

    def convert(pixels, name):
        write_window(tmp_path / f"{name}.exr", pixels, (0, 0, 64, 32), (0, 0, 64, pixels.shape[0]))
        result = run_cli(
            ["convert", tmp_path / f"{name}.exr", tmp_path / f"{name}-cross.exr", *common]
        )
        assert result.exit_code == 0, result.stderr
        return envconv.read(tmp_path / f"{name}-cross.exr").pixels

    half, whole = convert(sky[:13], "top"), convert(sky, "whole")
    alpha = half[:, :, 3]
    omega = naive.pixel_solid_angles("cube-vcross", 16, 8)
    held = (1 - np.sin(np.radians(90 - 13 / 32 * 180))) / 2
    assert (omega * alpha).sum() / omega.sum() == pytest.approx(held, abs=0.005)
    full = alpha == 1.0
    np.testing.assert_allclose(half[full][:, :3], whole[full][:, :3], rtol=1e-5)
    np.testing.assert_array_equal(half[alpha == 0], 0)
    flat = convert(np.full((13, 64, 3), 2.0, np.float32), "flat")
    rim = (flat[:, :, 3] > 0) & (flat[:, :, 3] < 1)
    assert rim.sum() > 20
    np.testing.assert_allclose(flat[flat[:, :, 3] > 0][:, :3], 2.0, rtol=1e-5)


def test_a_hole_leaks_nothing_into_a_magnified_map(tmp_path, sky):
    """The top 13 of 32 rows read 4 x magnified into a 256 x 128 lat-long (each output pixel
    inside one source texel), where the area filter integrates its linear reconstruction: the
    texels beside the hole (row 12) keep the box, so each of their pixels is exactly the texel's
    value (a slope there would read the hole's 0 and tilt the texel towards it); every texel
    whose stencil holds no hole (rows 0 to 11) gives the pixels of the whole map's conversion,
    slopes and all (its pixels vary inside a texel)."""
    write_window(tmp_path / "top.exr", sky[:13], (0, 0, 64, 32), (0, 0, 64, 13))
    top = envconv.convert(envconv.read(tmp_path / "top.exr"), "latlong", size=128)
    whole = envconv.convert(envconv.EnvMap(sky, "latlong"), "latlong", size=128)
    np.testing.assert_allclose(top.pixels[:48, :, :3], whole.pixels[:48], rtol=1e-6)
    assert np.ptp(whole.pixels[44:48, 8:12, 0]) > 1e-3  # slopes inside a texel of row 11
    beside = np.repeat(np.repeat(sky[12:13], 4, axis=0), 4, axis=1)
    np.testing.assert_allclose(top.pixels[48:52, :, :3], beside, rtol=1e-5)
    np.testing.assert_array_equal(top.pixels[52:], 0)


def test_overscan_beyond_the_display_window_is_cut_off(tmp_path, sky):
    """Data window 4 pixels larger than the display window on every side: the map is the
    display window's pixels alone, with nothing missing, so no alpha is added."""
    padded = np.pad(sky, ((4, 4), (4, 4), (0, 0)), mode="wrap")
    write_window(tmp_path / "over.exr", padded, (0, 0, 64, 32), (-4, -4, 72, 40))
    env = envconv.read(tmp_path / "over.exr")
    assert env.channels == ("R", "G", "B") and env.valid is None
    np.testing.assert_array_equal(env.pixels, sky)


def test_a_tiff_origin_places_its_pixels_as_an_exr_data_window_does(tmp_path, sky):
    """TIFF XPosition/YPosition (OIIO's x, y and full window): the same reading as EXR."""
    write_window(tmp_path / "o.tif", sky[:, :32], (0, 0, 64, 32), (32, 0, 32, 32))
    env = envconv.read(tmp_path / "o.tif")
    assert env.layout.name == "latlong"
    np.testing.assert_array_equal(env.pixels[:, 32:, :3], sky[:, :32])
    np.testing.assert_array_equal(env.pixels[:, :32], 0)
    np.testing.assert_array_equal(env.pixels[:, 32:, 3], 1)


def test_a_files_own_alpha_is_zero_in_holes_and_kept_elsewhere(tmp_path, sky):
    rgba = np.concatenate([sky, np.full((32, 64, 1), 0.25, np.float32)], axis=2)
    write_window(tmp_path / "rgba.exr", rgba[:16], (0, 0, 64, 32), (0, 0, 64, 16), names="RGBA")
    env = envconv.read(tmp_path / "rgba.exr")
    assert env.channels == ("R", "G", "B", "A")
    np.testing.assert_array_equal(env.pixels[:16], rgba[:16])
    np.testing.assert_array_equal(env.pixels[16:], 0)
    np.testing.assert_array_equal(env.valid[:16], 1)


def test_place_in_display_covers_every_overlap():
    """Against a direct per-pixel reading of the rule, for windows that overlap in every way."""
    rng = np.random.default_rng(3)
    display = (2, -1, 7, 5)
    for data in [(2, -1, 7, 5), (0, 0, 4, 3), (5, 2, 6, 6), (-3, -4, 20, 20), (20, 20, 2, 2)]:
        pixels = rng.random((data[3], data[2], 2)).astype(np.float32)
        image, valid = place_in_display(pixels, display, data)
        for j in range(display[3]):
            for i in range(display[2]):
                x, y = display[0] + i - data[0], display[1] + j - data[1]
                inside = 0 <= x < data[2] and 0 <= y < data[3]
                expect = pixels[y, x] if inside else np.zeros(2, np.float32)
                np.testing.assert_array_equal(image[j, i], expect)
                if valid is not None:
                    assert valid[j, i] == float(inside)
                else:
                    assert inside


def test_headers_report_both_windows(tmp_path, sky):
    write_window(tmp_path / "top.exr", sky[:16], (0, 0, 64, 32), (0, 0, 64, 16))
    header = read_file_header(tmp_path / "top.exr")
    assert header.display == (0, 0, 64, 32) and header.data == (0, 0, 64, 16) and header.holes
    width, height, channels, _ = envconv.io.read_header(tmp_path / "top.exr")
    assert (width, height, channels) == (64, 32, ("R", "G", "B", "A"))
    assert envconv.io.mip_levels(tmp_path / "top.exr") == [(64, 32)]


def test_dry_run_plans_the_display_window(tmp_path, sky):
    write_window(tmp_path / "top.exr", sky[:16], (0, 0, 64, 32), (0, 0, 64, 16))
    result = run_cli(["convert", tmp_path / "top.exr", tmp_path / "o.exr", "--to", "cube-vcross",
                      "--dry-run"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert "channels: R,G,B,A" in result.stdout


def test_from_a_layout_the_size_does_not_fit_says_which_sizes_would(tmp_path):
    """The hint no longer goes in a circle: it names the rule, sizes that fit, and what to do."""
    write_window(
        tmp_path / "odd.exr", np.ones((41, 50, 3), np.float32), (0, 0, 50, 41), (0, 0, 50, 41)
    )
    result = run_cli(["convert", tmp_path / "odd.exr", tmp_path / "o.exr", "--from", "latlong",
                      "--to", "cube-vcross"])  # fmt: skip
    assert result.exit_code == 1
    (line,) = stderr_lines(result)
    for words in (
        "latlong",
        "needs width = 2 × height",
        "50x41 is not",
        "82x41",
        "50x25",
        "crop or resize",
        "--from with the layout it is in",
        "fits no layout",
    ):
        assert words in line, (words, line)
    assert not os.path.exists(tmp_path / "o.exr")
    with pytest.raises(envconv.LayoutError, match="width:height = 3:4"):
        envconv.read(tmp_path / "odd.exr", layout="cube-vcross")


def test_an_unknown_aspect_lists_the_aspects_layouts_have(tmp_path):
    write_window(
        tmp_path / "odd.exr", np.ones((43, 63, 3), np.float32), (0, 0, 63, 43), (0, 0, 63, 43)
    )
    with pytest.raises(envconv.LayoutError) as info:
        envconv.read(tmp_path / "odd.exr")
    message = str(info.value)
    assert (
        "63x43" in message
        and "2:1 latlong or paraboloid" in message
        and "3:4 cube-vcross" in message
    )


def test_every_mip_level_treats_a_hole_as_a_hole(tmp_path):
    """A constant sky held above a hole: every level of the chain is the constant wherever it
    holds anything, and each level's alpha is the solid-angle-weighted block average of the
    level above it (the chain's own rule, docs/masks-guards-mips.md)."""
    write_window(
        tmp_path / "flat.exr", np.full((13, 64, 3), 3.0, np.float32), (0, 0, 64, 32), (0, 0, 64, 13)
    )
    env = envconv.read(tmp_path / "flat.exr")
    result = envconv.convert(env, "latlong", size=16, mips=True)
    assert len(result.levels) == 6
    for k, level in enumerate(result.levels):
        held = level[:, :, 3] > 0
        assert held.any() and (k > 2 or not held.all()), k
        np.testing.assert_allclose(level[held][:, :3], 3.0, rtol=1e-5)
        np.testing.assert_array_equal(level[~held], 0)
        if k and result.levels[k - 1].shape[0] >= 2:  # 2 x 2 blocks (down to 2 x 1)
            finer = result.levels[k - 1][:, :, 3]
            omega = naive.pixel_solid_angles("latlong", finer.shape[0], 8)
            shape = (level.shape[0], 2, level.shape[1], 2)
            blocks = (finer * omega).reshape(shape).sum(axis=(1, 3)) / omega.reshape(shape).sum(
                axis=(1, 3)
            )
            np.testing.assert_allclose(level[:, :, 3], blocks, atol=1e-4)
