"""envconv.read / envconv.write and layout detection: formats, channels, tags, files."""

from __future__ import annotations

import os

import analytic
import naive
import numpy as np
import pytest
from conftest import detect_layout, file_state, write_plain

import envconv
from envconv.engine.api import convert_file
from envconv.errors import ImageIOError, LayoutError
from envconv.io import read_image

# ---------------------------------------------------------------------------------------------
# Round trips per format


def _ramp(height, width, channels, hdr):
    """A smooth test image; HDR values (up to ~1000) for float formats, [0, 1] otherwise."""
    y, x = np.mgrid[0:height, 0:width]
    t = (x + 0.37 * y) / (width + 0.37 * height)
    planes = [t ** (1 + 0.4 * c) * (1 - 0.3 * (y / height)) for c in range(channels)]
    pixels = np.stack(planes, -1).astype(np.float32)
    return pixels * 1000.0 + 0.001 if hdr else pixels


# (extension, bit depth, channel counts, hdr data, check(result, original))
def _rel(tol):
    return lambda got, want: np.testing.assert_allclose(got, want, rtol=tol, atol=0)


def _abs(tol):
    return lambda got, want: np.testing.assert_allclose(got, want, rtol=0, atol=tol)


def _rgbe(got, want):
    # RGBE shares one exponent per pixel: error ≤ 2⁻⁸ of the pixel's largest channel.
    bound = want.max(axis=-1, keepdims=True) / 128.0
    assert np.all(np.abs(got - want) <= bound)


FORMATS = [
    (".exr", "float", (1, 3, 4, 5), True, _abs(0.0)),
    (".exr", "half", (1, 3, 4, 5), True, _rel(1e-3)),
    (".hdr", None, (3,), True, _rgbe),
    (".tif", "float", (1, 3, 4, 5), True, _abs(0.0)),
    (".tif", "uint16", (1, 3, 4, 5), False, _abs(2e-4)),
    (".tif", "uint8", (1, 3, 4), False, _abs(0.02)),
    (".png", "uint16", (1, 3, 4), False, _abs(2e-4)),
    (".png", "uint8", (1, 3, 4), False, _abs(0.02)),
    (".jpg", "uint8", (1, 3), False, _abs(0.05)),
]
CASES = [
    pytest.param(ext, depth, nch, hdr, check, id=f"{ext[1:]}-{depth}-{nch}ch")
    for ext, depth, counts, hdr, check in FORMATS
    for nch in counts
]


@pytest.mark.parametrize("ext, depth, nch, hdr, check", CASES)
def test_write_read_round_trip(tmp_path, ext, depth, nch, hdr, check):
    pixels = _ramp(16, 32, nch, hdr)
    path = tmp_path / f"map{ext}"
    written = envconv.write(envconv.EnvMap(pixels, "latlong"), path, bit_depth=depth)
    assert [os.fspath(p) for p in written] == [os.fspath(path)]
    back = envconv.read(path)
    assert back.pixels.dtype == np.float32
    assert back.pixels.shape == pixels.shape  # channel count kept
    assert back.layout.name == "latlong"
    check(back.pixels, pixels)
    if ext == ".exr":
        assert back.pixel_type == depth


@pytest.mark.parametrize("ext, keeps", [(".hdr", 3), (".jpg", 3), (".png", 4)])
def test_formats_with_fewer_channels_keep_the_first_ones(tmp_path, ext, keeps):
    pixels = _ramp(8, 16, 5, False)
    envconv.write(envconv.EnvMap(pixels, "latlong"), tmp_path / f"m{ext}")
    back = envconv.read(tmp_path / f"m{ext}")
    assert back.pixels.shape[2] == keeps
    np.testing.assert_allclose(back.pixels[..., :3], pixels[..., :3], atol=0.05)


def test_half_exr_keeps_hdr_range(tmp_path):
    pixels = np.full((8, 16, 3), 0.5, np.float32)
    pixels[3, 4] = [30000.0, 1e-3, 0.0]
    envconv.write(envconv.EnvMap(pixels, "latlong"), tmp_path / "h.exr", bit_depth="half")
    back = envconv.read(tmp_path / "h.exr").pixels
    np.testing.assert_allclose(back, pixels, rtol=1e-3, atol=1e-6)


# ---------------------------------------------------------------------------------------------
# Metadata and detection through files


@pytest.mark.parametrize(
    "name, envmap", [("latlong", "ENVMAP_LATLONG"), ("cube-exr", "ENVMAP_CUBE")]
)
def test_exr_envmap_attribute(tmp_path, name, envmap):
    import OpenEXR

    width, height = envconv.layouts.get_layout(name).image_size(8)
    envconv.write(envconv.EnvMap(np.ones((height, width, 3)), name), tmp_path / "m.exr")
    header = OpenEXR.File(os.fspath(tmp_path / "m.exr")).header()  # the file itself, not OIIO
    assert header["envmap"] == getattr(OpenEXR.Envmap, envmap)
    _, _, metadata, _ = read_image(tmp_path / "m.exr")
    assert metadata["envconv:layout"] == name
    assert envconv.read(tmp_path / "m.exr").layout.name == name


@pytest.mark.parametrize("name", ["sphere", "angular", "cube-vstrip", "paraboloid", "tennisball",
                                  "eac", "fisheye", "perspective"])  # fmt: skip
def test_layout_tag_is_read_back_for_ambiguous_aspects(tmp_path, name):
    import OpenEXR

    width, height = envconv.layouts.get_layout(name).image_size(8)
    envconv.write(envconv.EnvMap(np.ones((height, width, 3)), name), tmp_path / "m.exr")
    _, _, metadata, _ = read_image(tmp_path / "m.exr")
    assert metadata["envconv:layout"] == name
    assert "envmap" not in OpenEXR.File(os.fspath(tmp_path / "m.exr")).header()
    back = envconv.read(tmp_path / "m.exr")
    assert back.layout.name == name and back.size == 8


@pytest.mark.parametrize("ext", [".tif", ".jpg", ".png"])
def test_layout_and_guard_survive_formats_without_custom_attributes(tmp_path, ext):
    """TIFF and JPEG keep only their own tags: the layout, size and guard travel in
    ImageDescription (next to the input's own description), and a 1:1 guarded sphere map is
    read back as what it is, not refused as ambiguous."""
    width, height = envconv.layouts.get_layout("sphere").image_size(8, 2)
    sky = envconv.EnvMap(
        np.full((height, width, 3), 0.5, np.float32), "sphere", guard=2,
        metadata={"ImageDescription": "shot at noon"},
    )  # fmt: skip
    envconv.write(sky, tmp_path / f"m{ext}", warnings=[])
    back = envconv.read(tmp_path / f"m{ext}")
    assert (back.layout.name, back.size, back.guard) == ("sphere", 8, 2)
    assert back.metadata.get("ImageDescription") == "shot at noon"


@pytest.mark.parametrize(
    "value, name", [("LatLong Environment", "latlong"), ("CubeFace Environment", "cube-exr")]
)
def test_openexr_envmap_attribute_alone_is_enough(tmp_path, value, name):
    """A file from another tool: OpenEXR's envmap attribute but no envconv tag.

    OpenImageIO writes (and reports) the EXR ``envmap`` attribute as ``textureformat``.
    """
    import OpenEXR

    width, height = envconv.layouts.get_layout(name).image_size(8)
    write_plain(tmp_path / "m.exr", np.ones((height, width, 3)), {"textureformat": value})
    assert "envmap" in OpenEXR.File(os.fspath(tmp_path / "m.exr")).header()
    assert envconv.read(tmp_path / "m.exr").layout.name == name


def test_metadata_is_carried_to_the_output(tmp_path):
    env = envconv.EnvMap(np.ones((8, 16, 3)), "latlong", metadata={"Copyright": "CC0 test"})
    envconv.write(env, tmp_path / "a.exr")
    result = envconv.convert(envconv.read(tmp_path / "a.exr"), to="cube-vcross", size=4)
    envconv.write(result, tmp_path / "b.exr")
    back = envconv.read(tmp_path / "b.exr")
    assert back.metadata.get("Copyright") == "CC0 test"
    assert back.layout.name == "cube-vcross"


# ---------------------------------------------------------------------------------------------
# Detection from the aspect ratio


@pytest.mark.parametrize(
    "width, height, name",
    [(64, 32, "latlong"), (48, 64, "cube-vcross"), (64, 48, "cube-hcross"),
     (96, 16, "cube-hstrip")],
)  # fmt: skip
def test_unique_aspects_are_detected(tmp_path, width, height, name):
    pixels = np.full((height, width, 3), 0.25, np.float32)
    layout, guard = detect_layout(width, height, {}, pixels)
    assert layout.name == name and guard == 0
    write_plain(tmp_path / "plain.exr", pixels)
    assert envconv.read(tmp_path / "plain.exr").layout.name == name


@pytest.mark.parametrize(
    "width, height, candidates",
    [(32, 32, ("sphere", "angular", "fisheye")), (16, 96, ("cube-vstrip", "cube-exr")),
     (48, 32, ("tennisball", "eac"))],
)  # fmt: skip
def test_shared_aspects_raise_naming_the_candidates(tmp_path, width, height, candidates):
    pixels = np.full((height, width, 3), 0.25, np.float32)
    write_plain(tmp_path / "plain.exr", pixels)
    for call in (lambda: detect_layout(width, height, {}, pixels),
                 lambda: envconv.read(tmp_path / "plain.exr")):  # fmt: skip
        with pytest.raises(LayoutError) as info:
            call()
        message = str(info.value)
        assert all(name in message for name in candidates)
        assert "--from" in message and "\n" not in message
    assert envconv.read(tmp_path / "plain.exr", layout=candidates[1]).layout.name == candidates[1]


def test_untagged_packed_paraboloid_is_ambiguous(tmp_path):
    source = envconv.EnvMap(naive.pixel_average("latlong", 16, analytic.radiance, 2), "latlong")
    packed = envconv.convert(source, to="paraboloid", size=16)
    write_plain(tmp_path / "para.exr", packed.pixels)
    with pytest.raises(LayoutError) as info:
        envconv.read(tmp_path / "para.exr")
    assert "latlong" in str(info.value) and "paraboloid" in str(info.value)
    assert envconv.read(tmp_path / "para.exr", layout="paraboloid").layout.name == "paraboloid"


def test_normal_two_to_one_is_latlong(tmp_path):
    pixels = naive.pixel_average("latlong", 16, analytic.radiance, 2)
    write_plain(tmp_path / "ll.exr", pixels)
    assert envconv.read(tmp_path / "ll.exr").layout.name == "latlong"


def test_unknown_aspect_raises(tmp_path):
    write_plain(tmp_path / "odd.exr", np.ones((16, 30, 3)))
    with pytest.raises(LayoutError, match="30x16"):
        envconv.read(tmp_path / "odd.exr")


def test_forced_layout_that_does_not_fit_raises(tmp_path):
    write_plain(tmp_path / "ll.exr", np.ones((16, 32, 3)))
    with pytest.raises(LayoutError):
        envconv.read(tmp_path / "ll.exr", layout="cube-vcross")


# ---------------------------------------------------------------------------------------------
# Multi-file layouts


def test_cube_faces_write_six_named_files(tmp_path):
    n = 16
    source = envconv.EnvMap(naive.pixel_average("latlong", 32, analytic.smooth_radiance, 2),
                            "latlong")  # fmt: skip
    faces = envconv.convert(source, to="cube-faces", size=n)
    template = os.fspath(tmp_path / "sky_{face}.exr")
    written = envconv.write(faces, template)
    names = ["px", "nx", "py", "ny", "pz", "nz"]
    assert written == [template.replace("{face}", f) for f in names]
    # GL faces: px holds world −X, nx +X, py +Y, ny −Y, pz +Z, nz −Z (docs/geometry.md).
    centres = {"px": (-1, 0, 0), "nx": (1, 0, 0), "py": (0, 1, 0), "ny": (0, -1, 0),
               "pz": (0, 0, 1), "nz": (0, 0, -1)}  # fmt: skip
    for face, direction in centres.items():
        pixels, _, metadata, _ = read_image(template.replace("{face}", face))
        assert pixels.shape == (n, n, 3)
        assert metadata["envconv:face"] == face
        centre = pixels[n // 2 - 1 : n // 2 + 1, n // 2 - 1 : n // 2 + 1].mean((0, 1))
        np.testing.assert_allclose(centre, analytic.smooth_radiance(np.array(direction, float)),
                                   rtol=0.02)  # fmt: skip
    back = envconv.read(template)
    assert back.layout.name == "cube-faces"
    np.testing.assert_array_equal(back.pixels, faces.pixels)


def test_paraboloid_split_writes_front_and_back(tmp_path):
    source = envconv.EnvMap(naive.pixel_average("latlong", 16, analytic.radiance, 2), "latlong")
    halves = envconv.convert(source, to="paraboloid-split", size=8)
    template = os.fspath(tmp_path / "env_{face}.exr")
    assert envconv.write(halves, template) == [
        template.replace("{face}", "front"),
        template.replace("{face}", "back"),
    ]
    back = envconv.read(template)
    assert back.layout.name == "paraboloid-split"
    np.testing.assert_array_equal(back.pixels, halves.pixels)


def test_multi_file_path_without_face_raises(tmp_path):
    env = envconv.EnvMap(np.ones((4, 24, 3)), "cube-faces")
    with pytest.raises(LayoutError, match="{face}"):
        envconv.write(env, tmp_path / "sky.exr")
    assert os.listdir(tmp_path) == []


def test_face_in_path_of_single_file_layout_raises(tmp_path):
    env = envconv.EnvMap(np.ones((4, 8, 3)), "latlong")
    with pytest.raises(LayoutError):
        envconv.write(env, tmp_path / "sky_{face}.exr")
    assert os.listdir(tmp_path) == []


# ---------------------------------------------------------------------------------------------
# Errors, atomic writes, untouched inputs


def test_read_errors(tmp_path):
    with pytest.raises(ImageIOError, match="not found"):
        envconv.read(tmp_path / "missing.exr")
    garbage = tmp_path / "garbage.exr"
    garbage.write_bytes(b"this is not an OpenEXR file\n" * 10)
    with pytest.raises(ImageIOError):
        envconv.read(garbage)
    with pytest.raises(ImageIOError):
        envconv.read(tmp_path)


def test_unknown_extension_raises(tmp_path):
    with pytest.raises(envconv.UsageError, match=".xyz"):  # a bad argument: exit 2 in the CLI
        envconv.write(envconv.EnvMap(np.ones((4, 8, 3)), "latlong"), tmp_path / "m.xyz")
    assert os.listdir(tmp_path) == []


def _fail_on_face(monkeypatch, face_to_fail):
    """Make envconv.io fail while writing one file, after the real writer produced it."""
    import envconv.io.writer as io_module

    real = io_module._write_one

    def failing(temp, target, *args, **kwargs):
        real(temp, target, *args, **kwargs)
        assert os.path.exists(temp)  # the temporary file really was written
        if face_to_fail is None or face_to_fail in os.path.basename(target):
            raise ImageIOError(f"simulated failure writing {target}")

    monkeypatch.setattr(io_module, "_write_one", failing)


def test_failed_write_leaves_no_file_and_no_temp(tmp_path, monkeypatch):
    _fail_on_face(monkeypatch, None)
    with pytest.raises(ImageIOError):
        envconv.write(envconv.EnvMap(np.ones((4, 8, 3)), "latlong"), tmp_path / "out.exr")
    assert os.listdir(tmp_path) == []


def test_failed_multi_file_write_leaves_no_part(tmp_path, monkeypatch):
    _fail_on_face(monkeypatch, "_ny")
    with pytest.raises(ImageIOError):
        envconv.write(envconv.EnvMap(np.ones((4, 24, 3)), "cube-faces"), tmp_path / "s_{face}.exr")
    assert os.listdir(tmp_path) == []


def test_failed_write_keeps_an_existing_output(tmp_path, monkeypatch):
    target = tmp_path / "out.exr"
    envconv.write(envconv.EnvMap(np.ones((4, 8, 3)), "latlong"), target)
    before = file_state(target)
    _fail_on_face(monkeypatch, None)
    with pytest.raises(ImageIOError):
        envconv.write(envconv.EnvMap(np.zeros((4, 8, 3)), "latlong"), target)
    assert file_state(target) == before
    assert os.listdir(tmp_path) == ["out.exr"]


@pytest.mark.parametrize("ext", [".exr", ".hdr", ".png"])
def test_input_is_never_modified(tmp_path, ext):
    source = tmp_path / f"in{ext}"
    envconv.write(envconv.EnvMap(_ramp(16, 32, 3, False), "latlong"), source)
    before = file_state(source)
    convert_file(source, tmp_path / "out.exr", resample={"to": "cube-vcross", "size": 8})
    envconv.read(source)
    assert file_state(source) == before
    assert sorted(os.listdir(tmp_path)) == sorted([f"in{ext}", "out.exr"])


# ---------------------------------------------------------------------------------------------
# EXRs: OIIO reads every header and writes every file; the pixels of plain scanline files are
# decoded by the OpenEXR library. Checked against the other library reading the same file.


def _oiio_exr(path, pixels, names, pixel_type, tile=0, data_offset=0):
    """Write ``pixels`` with OIIO directly (not through envconv.write)."""
    import OpenImageIO as oiio

    height, width, nch = pixels.shape
    spec = oiio.ImageSpec(width, height, nch, pixel_type)
    spec.channelnames = tuple(names)
    if tile:
        spec.tile_width = spec.tile_height = tile
    if data_offset:
        spec.x = spec.y = data_offset
        spec.full_x = spec.full_y = 0
        spec.full_width, spec.full_height = width + data_offset, height + data_offset
    out = oiio.ImageOutput.create(os.fspath(path))
    assert out.open(os.fspath(path), spec)
    assert out.write_image(pixels)
    out.close()


def _oiio_pixels(path):
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(os.fspath(path))
    pixels = inp.read_image(oiio.FLOAT)
    inp.close()
    return pixels


def _oiio_metadata(path):
    """The ImageSpec attributes OIIO reads from ``path``, in its order."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(os.fspath(path))
    metadata = {a.name: a.value for a in inp.spec().extra_attribs}
    inp.close()
    return metadata


def _oiio_channel_names(path):
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(os.fspath(path))
    names = inp.spec().channelnames
    inp.close()
    return names


@pytest.mark.parametrize(
    "names, pixel_type",
    [
        (("R", "G", "B"), "float"),
        (("R", "G", "B", "A"), "half"),
        (("Y",), "float"),
        (("R", "G", "B", "A", "Z"), "float"),
        (("diffuse.R", "diffuse.G", "diffuse.B"), "half"),
    ],
)
def test_plain_exr_reads_as_oiio_does(tmp_path, monkeypatch, names, pixel_type):
    """OpenEXR decodes the pixels of a plain file OIIO wrote: they must be OIIO's own reading,
    bit for bit (inf and NaN included), with OIIO's channels and metadata."""
    import envconv.io.files as file_io_module

    rng = np.random.default_rng(4)
    pixels = (rng.standard_normal((12, 24, len(names))) * 100).astype(np.float32)
    pixels[0, 0, 0], pixels[1, 1, 0], pixels[2, 2, 0] = np.inf, -np.inf, np.nan
    path = tmp_path / "plain.exr"
    _oiio_exr(path, pixels, names, pixel_type)
    decoded = []
    original = file_io_module._read_exr_pixels
    monkeypatch.setattr(file_io_module, "_read_exr_pixels",
                        lambda *args: decoded.append(1) or original(*args))  # fmt: skip
    got, channels, metadata, stored = read_image(path)
    assert decoded == [1]
    assert stored == pixel_type
    assert channels == tuple(_oiio_channel_names(path))
    np.testing.assert_array_equal(got, _oiio_pixels(path))
    assert list(metadata.items()) == list(_oiio_metadata(path).items())


def _openexr_file(path, extra=None, dtype=np.float32, names="RGB", compression="ZIP_COMPRESSION",
                  parts=1):  # fmt: skip
    """Write a small scanline EXR with the OpenEXR library, header ``extra`` added."""
    import OpenEXR

    rng = np.random.default_rng(len(names))
    pixels = (rng.standard_normal((6, 10, len(names))) * 50).astype(dtype)
    header = {"type": OpenEXR.scanlineimage, "compression": getattr(OpenEXR, compression)}
    header.update(extra or {})
    channels = {names: pixels}
    if parts == 1:
        exr = OpenEXR.File(header, channels)
    else:
        exr = OpenEXR.File([OpenEXR.Part(dict(header), channels, f"part{k}") for k in range(parts)])
    with exr:
        exr.write(os.fspath(path))


def _openexr_cases():
    import OpenEXR

    chromaticities = (0.713, 0.293, 0.165, 0.83, 0.128, 0.044, 0.32168, 0.33767)
    return {
        "zip float": {},
        "latlong envmap": {"envmap": OpenEXR.Envmap.ENVMAP_LATLONG, "textureformat": "LatLong Environment"},
        "cube envmap": {"envmap": OpenEXR.Envmap.ENVMAP_CUBE},
        "ap1": {"chromaticities": chromaticities, "colorInteropID": "lin_ap1_scene"},
        "decreasing lines": {"lineOrder": OpenEXR.DECREASING_Y},
        "envconv tags": {"capDate": "2024:05:06 07:08:09", "Software": "envconv 0.1.0",
                         "envconv:layout": "latlong", "envconv:size": 3, "envconv:guard": 0},
        "odd window": {"pixelAspectRatio": 2.0, "screenWindowCenter": np.array([0.5, -1.0], np.float32),
                       "screenWindowWidth": 3.0},
        **{c: dict(compression=c) for c in ("NO_COMPRESSION", "RLE_COMPRESSION", "ZIPS_COMPRESSION",
                                            "PIZ_COMPRESSION", "PXR24_COMPRESSION", "B44_COMPRESSION",
                                            "B44A_COMPRESSION", "DWAA_COMPRESSION", "DWAB_COMPRESSION")},
        "half RGBA": dict(dtype=np.float16, names="RGBA"),
        "owner": {"owner": "someone"},
        "DWA level": {"dwaCompressionLevel": 80.0},
        "luminance": dict(names="Y"),
    }  # fmt: skip


@pytest.mark.parametrize("label", list(_openexr_cases()))
def test_exrs_written_by_openexr_read_as_oiio_reads_them(tmp_path, label):
    """Files the OpenEXR library wrote, with every compression and common attributes: envconv's
    reading (OIIO's header, OpenEXR's decode) must give OIIO's own pixels, channels, metadata
    and pixel type."""
    case = _openexr_cases()[label]
    known = {"compression", "dtype", "names", "parts"}
    _openexr_file(tmp_path / "case.exr", {k: v for k, v in case.items() if k not in known},
                  **{k: v for k, v in case.items() if k in known})  # fmt: skip
    pixels, channels, metadata, pixel_type = read_image(tmp_path / "case.exr")
    np.testing.assert_array_equal(
        pixels.reshape(-1), np.asarray(_oiio_pixels(tmp_path / "case.exr")).reshape(-1)
    )
    assert channels == tuple(_oiio_channel_names(tmp_path / "case.exr"))
    assert list(metadata.items()) == list(_oiio_metadata(tmp_path / "case.exr").items())
    assert pixel_type == ("half" if case.get("dtype") == np.float16 else "float")


@pytest.mark.parametrize("kind", ["tiled", "data window", "mixed types"])
def test_other_exrs_are_read_by_oiio(tmp_path, kind):
    import OpenImageIO as oiio

    pixels = np.random.default_rng(5).random((16, 32, 3)).astype(np.float32)
    path = tmp_path / "other.exr"
    if kind == "tiled":
        _oiio_exr(path, pixels, "RGB", "float", tile=16)
    elif kind == "data window":
        _oiio_exr(path, pixels, "RGB", "float", data_offset=2)
    else:
        spec = oiio.ImageSpec(32, 16, 3, oiio.FLOAT)
        spec.channelnames = ("R", "G", "B")
        spec.channelformats = (oiio.HALF, oiio.FLOAT, oiio.FLOAT)
        out = oiio.ImageOutput.create(os.fspath(path))
        assert out.open(os.fspath(path), spec) and out.write_image(pixels)
        out.close()
    got, *_ = read_image(path)
    expected = _oiio_pixels(path).reshape(16, 32, 3)
    if kind == "data window":  # stored at (2, 2) of an 34 x 18 display window; the rest empty
        expected = np.pad(expected, ((2, 0), (2, 0), (0, 0)))
    np.testing.assert_array_equal(got, expected)


def test_truncated_exr_is_a_one_line_error(tmp_path):
    path = tmp_path / "cut.exr"
    _oiio_exr(path, np.ones((64, 128, 3), np.float32), "RGB", "float")
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(ImageIOError) as info:
        envconv.read(path)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "layout, names, bit_depth, compression, metadata",
    [
        ("latlong", "RGB", "float", None, {"oiio:ColorSpace": "lin_rec709_scene"}),
        ("cube-vcross", "RGBA", "half", "none", {"DateTime": "2026:01:02 03:04:05"}),
        ("cube-exr", ("Y",), "float", "rle", {"oiio:ColorSpace": "lin_ap1_scene"}),
        ("latlong", ("R", "G", "B", "A", "Z"), "float", "piz", {"Copyright": "someone"}),
        ("latlong", "RGB", "half", "zips", {"oiio:ColorSpace": "lin_ap0_scene"}),
    ],
)
def test_exrs_envconv_writes_read_in_openexr_as_written(
    tmp_path, layout, names, bit_depth, compression, metadata
):
    """OpenEXR's own reader, independent of OIIO, finds in what envconv wrote the pixels
    (bit for bit at the stored type, inf and NaN included), the channels, the compression,
    OpenEXR's ``envmap`` for unguarded lat-longs and cubes, and the metadata: envconv's tags,
    the colour space as ``colorInteropID`` and ``chromaticities``, the capture date; and
    envconv reads the same back."""
    import OpenEXR

    rng = np.random.default_rng(6)
    width, height = envconv.layouts.get_layout(layout).image_size(8)
    pixels = (rng.standard_normal((height, width, len(names))) * 300).astype(np.float32)
    pixels[0, 0, 0], pixels[1, 1, 0] = np.inf, np.nan
    envmap = envconv.EnvMap(pixels, layout, channels=tuple(names), metadata=dict(metadata))
    path = tmp_path / "out.exr"
    envconv.write(envmap, path, bit_depth=bit_depth, compression=compression,
                  output_colorspace=metadata.get("oiio:ColorSpace"))  # fmt: skip
    stored = pixels.astype(np.float16 if bit_depth == "half" else np.float32)
    with OpenEXR.File(os.fspath(path), separate_channels=True) as exr:  # the header dies with it
        header, channels = dict(exr.header()), exr.channels()
        assert sorted(channels) == sorted(names)
        for k, name in enumerate(names):
            assert channels[name].pixels.dtype == stored.dtype
            np.testing.assert_array_equal(channels[name].pixels, stored[..., k])
    assert header["compression"] == getattr(OpenEXR, {None: "ZIP", "none": "NO"}.get(
        compression, str(compression).upper()) + "_COMPRESSION")  # fmt: skip
    assert (header["envconv:layout"], header["envconv:size"], header["envconv:guard"]) == (
        layout,
        8,
        0,
    )
    envmaps = {"latlong": OpenEXR.Envmap.ENVMAP_LATLONG, "cube-exr": OpenEXR.Envmap.ENVMAP_CUBE}
    assert header.get("envmap") == envmaps.get(layout)
    space = metadata.get("oiio:ColorSpace", "lin_rec709_scene")
    assert header["colorInteropID"] == space
    primaries = {"lin_rec709_scene": 0.64, "lin_ap1_scene": 0.713, "lin_ap0_scene": 0.7347}[space]
    assert header["chromaticities"][0] == pytest.approx(primaries)
    if "DateTime" in metadata:
        assert header["capDate"] == metadata["DateTime"]
    if "Copyright" in metadata:
        assert header["owner"] == metadata["Copyright"]
    back = envconv.read(path, input_colorspace="raw" if space != "lin_rec709_scene" else None)
    np.testing.assert_array_equal(back.pixels, stored.astype(np.float32))
    assert back.channels == tuple(names)


def test_openexr_thread_pool_follows_oiio_exr_threads():
    """OpenEXR decodes on as many threads as OIIO's public ``exr_threads`` asks (one in a
    batch worker, every core for 0), and on the calling thread alone for uncompressed or RLE
    data."""
    import OpenEXR
    import OpenImageIO as oiio

    from envconv.io.exr import _set_openexr_threads

    threads, pool = oiio.get_int_attribute("exr_threads"), OpenEXR.global_thread_count()
    try:
        oiio.attribute("exr_threads", 3)
        _set_openexr_threads("zip")
        assert OpenEXR.global_thread_count() == 3
        _set_openexr_threads("none")
        assert OpenEXR.global_thread_count() == 0
        oiio.attribute("exr_threads", 1)
        _set_openexr_threads("zip")
        assert OpenEXR.global_thread_count() == 0
        oiio.attribute("exr_threads", 0)  # OIIO's "all cores"
        _set_openexr_threads("piz")
        assert OpenEXR.global_thread_count() == (os.cpu_count() or 1)
    finally:
        oiio.attribute("exr_threads", threads)
        OpenEXR.set_global_thread_count(pool)
