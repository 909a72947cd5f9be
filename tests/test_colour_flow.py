"""Colour flow through reading, resampling and writing (envconv.color.ocio, envconv.color.prepare, envconv.io.encode, the CLI).

Truth comes from outside the code under test: integer codes chosen by the test, OCIO
processors built here with PyOpenColorIO, the sRGB formulas of IEC 61966-2-1, hand counts
of clipped pixels, and analytic functions sampled at edge-aligned positions.
"""

import math

import numpy as np
import OpenImageIO as oiio
import PyOpenColorIO as ocio
import pytest
from conftest import run_cli, stderr_lines, write_plain

from envconv import io
from envconv.color import ocio as color
from envconv.color import quantize
from envconv.envmap import EnvMap
from envconv.io import encode, formats, reader

H, W = 16, 32  # a lat-long of N = 16; latlong -> latlong at N = 16, samples 1 is 1:1


def read_raw(path, fmt=oiio.FLOAT):
    """Pixels exactly as stored (OIIO, no envconv), and the header attributes."""
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    pixels = inp.read_image(fmt)
    attrs = {a.name: a.value for a in inp.spec().extra_attribs}
    inp.close()
    return np.asarray(pixels), attrs


def ocio_truth(pixels, src, dst):
    """Apply OCIO's built-in default config processor src -> dst, computed here directly."""
    config = ocio.Config.CreateFromFile("ocio://default")
    cpu = config.getProcessor(src, dst).getDefaultCPUProcessor()
    rgb = np.ascontiguousarray(pixels[..., :3], np.float32).copy()
    cpu.applyRGB(rgb)
    return rgb


def srgb_decode(v):
    v = np.asarray(v, np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def one_to_one(src, dst, *extra):
    return run_cli(["convert", src, dst, "--to", "latlong", "--size", H, "--samples", 1, *extra])


def smooth_linear(scale=1.0):
    v, u = np.mgrid[0:H, 0:W].astype(np.float32)
    rgb = np.stack([(u + 0.5) / W, (v + 0.5) / H, 0.5 + 0.4 * np.sin(u / 3)], axis=2)
    return (rgb * scale).astype(np.float32)


# --- sRGB round trip -------------------------------------------------------------------------


@pytest.mark.parametrize("bit_depth", ["half", "float"])
def test_srgb_png_to_latlong_exr_and_back_keeps_8bit_codes(tmp_path, bit_depth):
    codes = np.random.default_rng(7).integers(0, 256, (H, W, 3), dtype=np.uint8)
    write_plain(tmp_path / "in.png", codes / 255.0, pixel_type="uint8")
    assert (
        one_to_one(tmp_path / "in.png", tmp_path / "mid.exr", "--bit-depth", bit_depth).exit_code
        == 0
    )
    mid, attrs = read_raw(tmp_path / "mid.exr")
    assert attrs["oiio:ColorSpace"] == "lin_rec709_scene"
    # The EXR holds linear light: the sRGB decode of the codes (IEC 61966-2-1).
    np.testing.assert_allclose(mid, srgb_decode(codes / 255.0), rtol=2e-3, atol=1e-6)
    assert one_to_one(tmp_path / "mid.exr", tmp_path / "back.png").exit_code == 0
    back, attrs = read_raw(tmp_path / "back.png", oiio.UINT8)
    assert np.abs(back.astype(int) - codes).max() <= 1
    assert attrs["oiio:ColorSpace"] == "srgb_rec709_scene"
    if bit_depth == "float":  # no half rounding: every code comes back exactly
        np.testing.assert_array_equal(back, codes)


def test_reading_a_png_gives_linear_light(tmp_path):
    codes = np.repeat(np.arange(512).reshape(H, W, 1) % 256, 3, axis=2) / 255.0  # every code
    write_plain(tmp_path / "ramp.png", codes, pixel_type="uint8")
    env = io.read(tmp_path / "ramp.png", layout="latlong")
    # OCIO's toe slope is the continuous 12.9232 (IEC rounds it to 12.92): 2.5e-4 relative.
    np.testing.assert_allclose(env.pixels, srgb_decode(codes), rtol=3e-4, atol=1e-7)


# --- ACEScg ----------------------------------------------------------------------------------


def test_exr_written_as_acescg_reads_back_as_linear_rec709(tmp_path):
    linear = smooth_linear(3.0)
    env = EnvMap(linear, "latlong")
    io.write(env, tmp_path / "cg.exr", bit_depth="float", output_colorspace="ACEScg")
    stored, attrs = read_raw(tmp_path / "cg.exr")
    assert attrs["oiio:ColorSpace"] == "lin_ap1_scene"
    assert attrs["chromaticities"][:2] == pytest.approx((0.713, 0.293), abs=1e-6)  # AP1 red
    np.testing.assert_allclose(stored, ocio_truth(linear, "lin_rec709_scene", "lin_ap1_scene"),
                               rtol=1e-5, atol=1e-6)  # fmt: skip
    back = io.read(tmp_path / "cg.exr")
    np.testing.assert_allclose(back.pixels, ocio_truth(stored, "ACEScg", "Linear Rec.709 (sRGB)"),
                               rtol=1e-5, atol=1e-6)  # fmt: skip
    np.testing.assert_allclose(back.pixels, linear, rtol=1e-4, atol=1e-5)


def test_acescg_file_from_another_tool_is_converted_on_read(tmp_path):
    values = smooth_linear(2.0)
    write_plain(tmp_path / "other.exr", values, {"oiio:ColorSpace": "ACEScg"})
    env = io.read(tmp_path / "other.exr")
    np.testing.assert_allclose(env.pixels, ocio_truth(values, "ACEScg", "lin_rec709_scene"),
                               rtol=1e-5, atol=1e-6)  # fmt: skip
    forced = io.read(tmp_path / "other.exr", input_colorspace="linear")  # override: as stored
    np.testing.assert_array_equal(forced.pixels, values)


def test_grey_and_alpha_are_not_colour_converted(tmp_path):
    rgba = np.concatenate([smooth_linear(), np.full((H, W, 1), 0.25, np.float32)], axis=2)
    write_plain(tmp_path / "a.png", rgba, pixel_type="uint16")
    env = io.read(tmp_path / "a.png", layout="latlong")
    np.testing.assert_allclose(env.pixels[..., 3], round(0.25 * 65535) / 65535, atol=1e-7)


# --- warnings: clipping and half overflow ----------------------------------------------------


def test_clipping_warning_gives_the_fraction_of_pixels(tmp_path):
    px = smooth_linear(0.5)
    px[:4, :, 1] = 4.0  # 4 of 16 rows: 25% of pixels above 1 in one channel
    write_plain(tmp_path / "hdr.exr", px)
    result = one_to_one(tmp_path / "hdr.exr", tmp_path / "out.png")
    assert result.exit_code == 0
    lines = [line for line in stderr_lines(result) if "warning" in line]
    assert len(lines) == 1 and "clips 25% of pixels" in lines[0], lines


def test_no_clipping_warning_in_range_or_for_float(tmp_path):
    write_plain(tmp_path / "ldr.exr", smooth_linear(0.9))
    assert stderr_lines(one_to_one(tmp_path / "ldr.exr", tmp_path / "out.png")) == []
    hot = smooth_linear(0.5)
    hot[0] = 1e4
    write_plain(tmp_path / "hot.exr", hot)
    assert (
        stderr_lines(one_to_one(tmp_path / "hot.exr", tmp_path / "out.tif", "--bit-depth", "float"))
        == []
    )


def test_half_overflow_warns_only_past_65504(tmp_path):
    px = smooth_linear()
    px[:2, :, 0] = 1e5  # 2 of 16 rows: 12.5% of pixels
    write_plain(tmp_path / "big.exr", px)
    result = one_to_one(tmp_path / "big.exr", tmp_path / "out.exr", "--bit-depth", "half")
    lines = stderr_lines(result)
    assert len(lines) == 1 and "12.5% of pixels" in lines[0] and "65504" in lines[0], lines
    stored, _ = read_raw(tmp_path / "out.exr")
    assert stored[:2, :, 0].max() == 65504.0
    px[:2, :, 0] = 60000.0
    write_plain(tmp_path / "near.exr", px)
    assert (
        stderr_lines(
            one_to_one(tmp_path / "near.exr", tmp_path / "out2.exr", "--bit-depth", "half")
        )
        == []
    )
    px[:2, :, 0] = 1e5
    write_plain(tmp_path / "big2.exr", px)
    assert (
        stderr_lines(
            one_to_one(tmp_path / "big2.exr", tmp_path / "out3.exr", "--bit-depth", "float")
        )
        == []
    )


def test_exposure_scales_before_writing(tmp_path):
    px = smooth_linear(4.0)
    write_plain(tmp_path / "in.exr", px)
    result = one_to_one(
        tmp_path / "in.exr", tmp_path / "out.exr", "--exposure", "-2", "--bit-depth", "float"
    )
    assert result.exit_code == 0
    np.testing.assert_allclose(read_raw(tmp_path / "out.exr")[0], px / 4, rtol=1e-6)
    assert (
        stderr_lines(one_to_one(tmp_path / "in.exr", tmp_path / "o.png", "--exposure", "-2")) == []
    )


def test_clamp_negative(tmp_path):
    px = smooth_linear()
    px[3, 5] = [-2.0, 0.5, -0.1]
    write_plain(tmp_path / "neg.exr", px)
    one_to_one(tmp_path / "neg.exr", tmp_path / "kept.exr", "--bit-depth", "float")
    assert read_raw(tmp_path / "kept.exr")[0][3, 5].tolist() == [-2.0, 0.5, pytest.approx(-0.1)]
    one_to_one(
        tmp_path / "neg.exr", tmp_path / "zero.exr", "--clamp-negative", "--bit-depth", "float"
    )
    assert read_raw(tmp_path / "zero.exr")[0][3, 5].tolist() == [0.0, 0.5, 0.0]


# --- NaN and Inf ------------------------------------------------------------------------------


def test_nonfinite_values_are_reported_and_fixed(tmp_path):
    px = smooth_linear()
    px[5, 7, 0], px[9, 2, 2], px[9, 3, 1] = np.nan, np.inf, np.nan
    write_plain(tmp_path / "bad.exr", px)
    kept = one_to_one(tmp_path / "bad.exr", tmp_path / "kept.exr")
    lines = stderr_lines(kept)
    assert len(lines) == 1 and "2 NaN and 1 Inf" in lines[0] and "--fix-nonfinite" in lines[0]
    fixed = one_to_one(tmp_path / "bad.exr", tmp_path / "fixed.exr", "--fix-nonfinite", "box3",
                       "--bit-depth", "float")  # fmt: skip
    assert fixed.exit_code == 0 and "replaced" in stderr_lines(fixed)[0]
    out = read_raw(tmp_path / "fixed.exr")[0]
    assert np.isfinite(out).all()
    neighbours = np.delete(px[4:7, 6:9, 0].ravel(), 4)  # 3x3 around (5, 7) minus the centre
    assert out[5, 7, 0] == pytest.approx(neighbours.mean(), rel=1e-6)
    stopped = one_to_one(tmp_path / "bad.exr", tmp_path / "x.exr", "--fix-nonfinite", "error")
    assert stopped.exit_code == 1 and len(stderr_lines(stopped)) == 1
    assert not (tmp_path / "x.exr").exists()


def test_nan_stays_in_its_channel_through_a_matrix_conversion():
    px = smooth_linear()
    px[2, 3, 0] = np.nan
    env = EnvMap(px, "latlong", metadata={"oiio:ColorSpace": "ACEScg"})
    out = color.to_working(env).pixels
    assert np.isnan(out[2, 3, 0]) and np.isfinite(out[2, 3, 1:]).all()
    assert np.isfinite(np.delete(out.reshape(-1, 3), 2 * W + 3, axis=0)).all()


# --- dither -----------------------------------------------------------------------------------


def test_dithering_is_deterministic_and_on_by_default(tmp_path):
    v, u = np.mgrid[0:H, 0:W]
    ramp = np.repeat((0.2 + 0.05 * u / W + 0.001 * v)[..., None], 3, axis=2).astype(np.float32)
    write_plain(tmp_path / "ramp.exr", ramp)
    one_to_one(tmp_path / "ramp.exr", tmp_path / "a.png")
    one_to_one(tmp_path / "ramp.exr", tmp_path / "b.png")
    one_to_one(tmp_path / "ramp.exr", tmp_path / "plain.png", "--no-dither")
    a, b = read_raw(tmp_path / "a.png", oiio.UINT8)[0], read_raw(tmp_path / "b.png", oiio.UINT8)[0]
    plain = read_raw(tmp_path / "plain.png", oiio.UINT8)[0]
    np.testing.assert_array_equal(a, b)
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()
    assert not np.array_equal(a, plain) and np.abs(a.astype(int) - plain).max() <= 1


# --- edge-aligned lat-longs (oiio:sampleborder) -----------------------------------------------


def analytic(u, v):
    """A smooth function of direction, via docs/geometry.md's lat-long formula."""
    lon, lat = 2 * np.pi * (0.5 - u), np.pi * (0.5 - v)
    x, y, z = np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)
    return np.stack([1 + 0.5 * x, 1 + 0.5 * y, 1 + 0.5 * z], axis=-1)


def test_sampleborder_latlong_is_resampled_to_pixel_centres(tmp_path):
    h, w = 32, 64
    j, i = np.mgrid[0:h, 0:w].astype(np.float64)
    edge = analytic(i / (w - 1), j / (h - 1))  # ImfEnvmap: samples on the edges
    path = tmp_path / "imf.exr"
    write_plain(path, edge, {"textureformat": "LatLong Environment"})
    assert read_raw(path)[1].get("oiio:sampleborder") == 1  # OIIO: envmap attribute => border
    env = io.read(path)
    centre = analytic((i + 0.5) / w, (j + 0.5) / h)
    np.testing.assert_allclose(env.pixels, centre, atol=1.5e-3)  # linear interpolation error
    assert np.abs(edge - centre).max() > 0.02  # read as stored it would be off by half a pixel


def test_envconvs_own_latlong_exr_is_not_resampled(tmp_path):
    px = smooth_linear()
    io.write(EnvMap(px, "latlong"), tmp_path / "own.exr", bit_depth="float")
    # The file says its samples are centred (envconv.io.exr_header), and OIIO reads it so.
    assert read_raw(tmp_path / "own.exr")[1].get("oiio:sampleborder") == 0
    np.testing.assert_array_equal(io.read(tmp_path / "own.exr").pixels, px)


def test_older_envconv_latlong_exr_is_not_resampled(tmp_path):
    """A lat-long from an envconv before oiio:sampleborder = 0 was stored: OIIO reports 1 (its
    envmap default), and the envconv:layout tag says the samples are envconv's centres."""
    px = smooth_linear()
    tags = {"textureformat": "LatLong Environment", "envconv:layout": "latlong"}
    write_plain(tmp_path / "old.exr", px, tags)
    assert read_raw(tmp_path / "old.exr")[1].get("oiio:sampleborder") == 1
    np.testing.assert_array_equal(io.read(tmp_path / "old.exr").pixels, px)


def test_resample_edge_aligned_is_exact_for_linear_functions():
    h, w = 5, 9
    j, i = np.mgrid[0:h, 0:w].astype(np.float64)
    edge = (3 * i / (w - 1) - 2 * j / (h - 1))[..., None]
    out = reader.resample_edge_aligned(edge)
    np.testing.assert_allclose(out[..., 0], 3 * (i + 0.5) / w - 2 * (j + 0.5) / h, atol=1e-6)


# --- planning and validation ------------------------------------------------------------------


def test_plan_output_defaults():
    plan = encode.plan_output("x.png", "float", {})
    assert (plan.pixel_type, plan.metadata_colorspace) == ("uint8", "srgb_rec709_scene")
    plan = encode.plan_output("x.exr", "uint8", {}, output_colorspace="acescg")
    assert (plan.pixel_type, plan.metadata_colorspace) == ("half", "lin_ap1_scene")
    plan = encode.plan_output("x.tif", "uint16", {"oiio:ColorSpace": "lin_rec709_scene"})
    assert (plan.pixel_type, plan.colorspace) == ("uint16", "sRGB Encoded Rec.709 (sRGB)")
    assert formats.check_compression("openexr", "DWAA:45") == "dwaa:45"
    assert math.isfinite(quantize.HALF_MAX)
