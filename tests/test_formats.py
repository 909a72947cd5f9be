"""File formats, bit depths, compression, metadata and --dry-run, through the CLI.

Inputs are written with OpenImageIO directly (conftest.write_plain) from values chosen here;
outputs are re-opened with OpenImageIO, so envconv's reader is not its own judge.
"""

import json

import numpy as np
import OpenImageIO as oiio
import pytest
from conftest import run_cli, stderr_lines, write_plain

from envconv import io

H, W = 16, 32  # lat-long N = 16


def read_raw(path, fmt=oiio.FLOAT):
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    spec = inp.spec()
    pixels = np.asarray(inp.read_image(fmt))
    attrs = {a.name: a.value for a in spec.extra_attribs}
    kind = str(spec.format)
    inp.close()
    return pixels, attrs, kind


def srgb_encode(x):
    x = np.asarray(x, np.float64)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.maximum(x, 0) ** (1 / 2.4) - 0.055)


def linear_values(scale=1.0):
    v, u = np.mgrid[0:H, 0:W].astype(np.float32)
    rgb = np.stack([(u + 0.5) / W, (v + 0.5) / H, 0.25 + 0.2 * np.cos(u / 4)], axis=2)
    return (rgb * scale).astype(np.float32)


def convert(src, dst, *extra):
    return run_cli(["convert", src, dst, "--to", "latlong", "--size", H, "--samples", 1, *extra])


# --- Radiance HDR and TIFF -------------------------------------------------------------------


def test_hdr_out_and_in(tmp_path):
    px = linear_values(50.0)
    write_plain(tmp_path / "in.exr", px)
    result = convert(tmp_path / "in.exr", tmp_path / "out.hdr")
    assert result.exit_code == 0 and stderr_lines(result) == []
    stored, attrs, kind = read_raw(tmp_path / "out.hdr")
    assert kind == "float"
    # RGBE: an 8-bit mantissa per channel under the largest channel's exponent.
    assert (np.abs(stored - px) <= px.max(axis=2, keepdims=True) / 128).all()
    back = convert(tmp_path / "out.hdr", tmp_path / "back.exr", "--bit-depth", "float")
    assert back.exit_code == 0
    np.testing.assert_allclose(read_raw(tmp_path / "back.exr")[0], stored, rtol=1e-6)


def test_hdr_cannot_store_negatives_and_says_so(tmp_path):
    px = linear_values()
    px[:4, :, 2] = -0.5  # 25% of pixels
    write_plain(tmp_path / "neg.exr", px)
    result = convert(tmp_path / "neg.exr", tmp_path / "out.hdr")
    lines = stderr_lines(result)
    assert len(lines) == 1 and "negative" in lines[0] and "25% of pixels" in lines[0]
    assert read_raw(tmp_path / "out.hdr")[0][:4, :, 2].max() == 0.0


def test_tiff_float_in_and_out_is_exact(tmp_path):
    px = linear_values(7.0)
    px[0, 0] = [-1.5, 1e6, 3e-7]
    write_plain(tmp_path / "in.tif", px)
    assert convert(tmp_path / "in.tif", tmp_path / "out.tif").exit_code == 0
    stored, attrs, kind = read_raw(tmp_path / "out.tif")
    assert kind == "float"  # TIFF keeps no colour space: float means linear, the default
    np.testing.assert_array_equal(stored, px)


def test_tiff_uint16_in_and_out(tmp_path):
    codes = np.random.default_rng(2).integers(0, 65536, (H, W, 3))
    write_plain(tmp_path / "in.tif", codes / 65535.0, pixel_type="uint16")
    assert convert(tmp_path / "in.tif", tmp_path / "out.tif").exit_code == 0
    stored, attrs, kind = read_raw(tmp_path / "out.tif", oiio.UINT16)
    assert kind == "uint16"
    assert np.abs(stored.astype(np.int64) - codes).max() <= 1
    # float EXR -> 16-bit TIFF: sRGB-encoded codes (IEC formula; OCIO's toe differs by 2.5e-4)
    px = linear_values()
    write_plain(tmp_path / "lin.exr", px)
    assert (
        convert(tmp_path / "lin.exr", tmp_path / "enc.tif", "--bit-depth", "uint16").exit_code == 0
    )
    enc = read_raw(tmp_path / "enc.tif", oiio.UINT16)[0].astype(np.float64)
    np.testing.assert_allclose(enc, srgb_encode(px) * 65535, atol=1.5)


def test_linear_output_colorspace_for_integer_files(tmp_path):
    px = linear_values()
    write_plain(tmp_path / "lin.exr", px)
    result = convert(tmp_path / "lin.exr", tmp_path / "lin.png", "--bit-depth", "uint16",
                     "--output-colorspace", "linear")  # fmt: skip
    assert result.exit_code == 0 and stderr_lines(result) == []
    stored, attrs, _ = read_raw(tmp_path / "lin.png", oiio.UINT16)
    assert attrs["oiio:ColorSpace"] == "lin_rec709_scene"
    np.testing.assert_array_equal(stored, np.rint(px * 65535))
    np.testing.assert_allclose(io.read(tmp_path / "lin.png").pixels, px, atol=1 / 65535)


def test_tiff_cannot_record_a_non_default_colour_space_and_says_so(tmp_path):
    px = linear_values()
    write_plain(tmp_path / "lin.exr", px)
    result = convert(tmp_path / "lin.exr", tmp_path / "lin.tif", "--bit-depth", "uint16",
                     "--output-colorspace", "linear")  # fmt: skip
    lines = stderr_lines(result)
    assert result.exit_code == 0 and len(lines) == 1 and "--input-colorspace" in lines[0]
    back = io.read(tmp_path / "lin.tif", input_colorspace="linear")
    np.testing.assert_allclose(back.pixels, px, atol=1 / 65535)
    assert (
        stderr_lines(convert(tmp_path / "lin.exr", tmp_path / "srgb.tif", "--bit-depth", "uint16"))
        == []
    )


# --- bit depth and compression ---------------------------------------------------------------


@pytest.mark.parametrize("src_type, ext, expected", [("half", "exr", "half"), ("float", "exr", "float"),
                                                      ("uint8", "exr", "half"), ("uint16", "tif", "uint16"),
                                                      ("float", "png", "uint8"), ("uint16", "png", "uint16")])  # fmt: skip
def test_default_bit_depth_follows_the_input(tmp_path, src_type, ext, expected):
    write_plain(tmp_path / ("in.exr" if src_type in ("half", "float") else "in.tif"),
                linear_values(0.9), pixel_type=src_type)  # fmt: skip
    src = tmp_path / ("in.exr" if src_type in ("half", "float") else "in.tif")
    assert convert(src, tmp_path / f"out.{ext}").exit_code == 0
    assert read_raw(tmp_path / f"out.{ext}")[2] == expected


def test_bit_depth_the_format_cannot_store_is_a_one_line_error(tmp_path):
    write_plain(tmp_path / "in.exr", linear_values())
    result = convert(tmp_path / "in.exr", tmp_path / "out.exr", "--bit-depth", "uint8")
    assert result.exit_code == 2 and len(stderr_lines(result)) == 1  # arguments that contradict
    assert "half, float" in result.stderr and not (tmp_path / "out.exr").exists()


@pytest.mark.parametrize("name", ["piz", "dwaa", "zip", "none", "b44"])
def test_exr_compression_is_written(tmp_path, name):
    write_plain(tmp_path / "in.exr", linear_values())
    assert convert(tmp_path / "in.exr", tmp_path / "out.exr", "--compression", name).exit_code == 0
    assert read_raw(tmp_path / "out.exr")[1]["compression"] == name


def test_unknown_compression_names_the_choices(tmp_path):
    write_plain(tmp_path / "in.exr", linear_values())
    result = convert(tmp_path / "in.exr", tmp_path / "out.exr", "--compression", "lzma")
    assert result.exit_code == 2 and len(stderr_lines(result)) == 1  # a bad option value: usage
    assert "piz" in result.stderr and "dwaa" in result.stderr and "Traceback" not in result.output
    png = convert(tmp_path / "in.exr", tmp_path / "out.png", "--compression", "zip")
    assert png.exit_code == 2 and "png" in png.stderr


# --- metadata --------------------------------------------------------------------------------


REC709 = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290)


def test_metadata_survives_a_round_trip(tmp_path):
    src = tmp_path / "in.exr"
    attrs = {"Copyright": "Jane Roe", "ImageDescription": "test sky, 2024", "Owner": "studio"}
    write_plain(src, linear_values(), attrs)
    spec_fix = oiio.ImageBuf(str(src))  # add chromaticities with their proper float[8] type
    spec_fix.specmod().attribute("chromaticities", oiio.TypeDesc("float[8]"), REC709)
    assert spec_fix.write(str(tmp_path / "in2.exr"))
    result = run_cli(
        ["convert", tmp_path / "in2.exr", tmp_path / "out.exr", "--to", "cube-hcross", "--size", 8]
    )
    assert result.exit_code == 0
    _, out, _ = read_raw(tmp_path / "out.exr")
    assert out["Copyright"] == "Jane Roe" and out["ImageDescription"] == "test sky, 2024"
    assert out["Owner"] == "studio"
    assert out["chromaticities"] == pytest.approx(REC709, abs=1e-6)
    assert out["oiio:ColorSpace"] == "lin_rec709_scene"
    assert (out["envconv:layout"], out["envconv:size"], out["envconv:guard"]) == (
        "cube-hcross",
        8,
        0,
    )
    assert out["envconv:version"]
    info = run_cli(["info", tmp_path / "out.exr", "--json"])
    record = json.loads(info.stdout)
    assert record["colorspace"] == "Linear Rec.709 (sRGB)"
    for key in ("Copyright", "ImageDescription", "chromaticities", "envconv:layout",
                "envconv:size", "envconv:guard", "envconv:version", "compression"):  # fmt: skip
        assert key in record["metadata"], key


def test_converting_the_colour_space_replaces_stale_chromaticities(tmp_path):
    buf = oiio.ImageBuf(oiio.ImageSpec(W, H, 3, oiio.FLOAT))
    buf.set_pixels(oiio.ROI(), linear_values())
    buf.specmod().attribute("chromaticities", oiio.TypeDesc("float[8]"), REC709)
    assert buf.write(str(tmp_path / "in.exr"))
    convert(tmp_path / "in.exr", tmp_path / "cg.exr", "--output-colorspace", "ACEScg")
    _, out, _ = read_raw(tmp_path / "cg.exr")
    assert out["oiio:ColorSpace"] == "lin_ap1_scene"
    assert out["chromaticities"][:2] == pytest.approx((0.713, 0.293), abs=1e-6)


# --- dry run ---------------------------------------------------------------------------------


def test_dry_run_prints_the_plan_and_writes_nothing(tmp_path):
    write_plain(tmp_path / "in.exr", linear_values(), pixel_type="half")
    result = run_cli(["convert", tmp_path / "in.exr", tmp_path / "sky_{face}.png", "--to",
                      "cube-faces", "--size", 8, "--alpha", "--dry-run"])  # fmt: skip
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "layout: cube-faces" in out and "size: 8 (8x8 per file" in out
    assert "channels: R,G,B,A" in out and "bit depth: uint8" in out
    assert "Linear Rec.709 (sRGB) -> Linear Rec.709 (sRGB) (working) -> sRGB Encoded Rec.709" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.exr"]
    for face in ("px", "nx", "py", "ny", "pz", "nz"):
        assert f"would write: {tmp_path / f'sky_{face}.png'}" in out


def test_dry_run_reads_only_the_header(tmp_path):
    write_plain(tmp_path / "in.exr", linear_values())
    data = (tmp_path / "in.exr").read_bytes()
    (tmp_path / "cut.exr").write_bytes(data[: len(data) - 200])  # header intact, pixels not
    dry = run_cli(
        ["convert", tmp_path / "cut.exr", tmp_path / "o.hdr", "--to", "latlong", "--dry-run"]
    )
    assert (
        dry.exit_code == 0 and "bit depth: float" in dry.stdout and "channels: R,G,B" in dry.stdout
    )
    real = run_cli(["convert", tmp_path / "cut.exr", tmp_path / "o.hdr", "--to", "latlong"])
    assert real.exit_code == 1 and not (tmp_path / "o.hdr").exists()


@pytest.mark.parametrize(
    "path",
    ["a.exr", "A.EXR", "dir/x.tar.gz", ".hidden", "a.", "a..b", "noext", "d.d/x", "./a.hdr",
     "a.b.", ".a.exr", "/x/y/.z.png", "sky.cube.dds"],
)  # fmt: skip
def test_extension_is_what_pathlib_calls_the_suffix(path):
    from pathlib import Path

    from envconv.io.formats import extension

    assert extension(path) == Path(path).suffix.lower()
