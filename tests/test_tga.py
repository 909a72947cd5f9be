"""Targa output, as game skyboxes (Quake II/III, GoldSrc, Source) load it.

Files are decoded here by a reader written from the Targa 2.0 specification, not OpenImageIO:
an 18-byte header (id length, colour-map type 0, image type 2 = uncompressed true colour,
width, height, bits per pixel, the image descriptor: alpha bits in 0-3, bit 5 the origin,
clear for bottom-left), then BGR(A) rows. Quake II's ``LoadTGA`` (ref_gl/gl_image.c) reads the
rows bottom-up whatever bit 5 says and takes only types 2 and 10; Quake III's (tr_image.c)
honours bit 5. A file with bit 5 clear and its rows stored bottom-up is upright in both, which
is what is checked: the decoded picture, top row first, is the map's.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest
from conftest import run_cli, stderr_lines

import envconv
from envconv.layouts.facesets import face_to_file, get_face_set


def decode_tga(path) -> tuple[dict, np.ndarray]:
    """(header fields, pixels (H, W, C) uint8 RGB(A), top row first) of an uncompressed Targa,
    its rows taken bottom-up as Quake II does."""
    data = open(path, "rb").read()
    id_length, cmap_type, image_type = data[0], data[1], data[2]
    width, height = struct.unpack("<HH", data[12:16])
    bpp, descriptor = data[16], data[17]
    header = {"id_length": id_length, "colour_map": cmap_type, "type": image_type,
              "width": width, "height": height, "bpp": bpp,
              "alpha_bits": descriptor & 0x0F, "top_left_origin": bool(descriptor & 0x20)}  # fmt: skip
    assert image_type == 2, "only uncompressed true colour is decoded here"
    nch = bpp // 8
    start = 18 + id_length
    stored = np.frombuffer(data[start : start + width * height * nch], np.uint8)
    rows = stored.reshape(height, width, nch)[::-1]  # bottom-up: the last stored row is the top
    rgb = rows[..., [2, 1, 0, 3][:nch]]  # BGR(A) → RGB(A)
    return header, np.ascontiguousarray(rgb)


def _srgb8(linear) -> np.ndarray:
    x = np.clip(np.asarray(linear, np.float64), 0, 1)
    encoded = np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)
    return np.round(encoded * 255).astype(int)


def _gradient(height, width, nch=3):
    """A picture that is upside down, mirrored or turned in no way that keeps it."""
    v, u = np.mgrid[0:height, 0:width].astype(np.float32)
    rgb = [(u + 0.5) / width, (v + 0.5) / height, 0.2 + 0.6 * ((u + 2 * v) % 5) / 5]
    if nch == 4:
        rgb.append(np.where(v < height / 2, 1.0, 0.5).astype(np.float32))
    return np.stack(rgb, -1).astype(np.float32)


@pytest.mark.parametrize("nch", [3, 4])
def test_tga_is_uncompressed_bottom_up_and_upright(tmp_path, nch):
    pixels = _gradient(16, 32, nch)
    sky = envconv.EnvMap(pixels, "latlong")
    envconv.io.write(sky, tmp_path / "sky.tga", dither=False)
    header, decoded = decode_tga(tmp_path / "sky.tga")
    assert header == {"id_length": 0, "colour_map": 0, "type": 2, "width": 32, "height": 16,
                      "bpp": 8 * nch, "alpha_bits": 8 if nch == 4 else 0,
                      "top_left_origin": False}  # fmt: skip
    expected = _srgb8(pixels[..., :3])  # sRGB by default, as PNG
    assert np.abs(decoded[..., :3].astype(int) - expected).max() <= 1
    if nch == 4:  # alpha as written, never multiplied into the colour
        np.testing.assert_array_equal(decoded[..., 3], np.where(pixels[..., 3] == 1, 255, 128))
    back = envconv.io.read(tmp_path / "sky.tga")  # and envconv reads it back, tagged or not
    np.testing.assert_allclose(back.pixels[..., :3], pixels[..., :3], atol=0.02)


def test_quake_face_set_writes_upright_tga_faces(tmp_path):
    """``sky_{face}.tga`` with the quake set: six files named lf rt up dn ft bk, each the
    envconv face turned as the set says, upright for the game's loader; read back, the map."""
    rng = np.random.default_rng(2)
    faces = rng.random((8, 48, 3)).astype(np.float32)
    cube = envconv.EnvMap(faces, "cube-faces")
    written = envconv.io.write(cube, tmp_path / "sky_{face}.tga", faces="quake", dither=False)
    quake = get_face_set("quake")
    assert [p.rsplit("_", 1)[1] for p in written] == [f"{n}.tga" for n in quake.names]
    for k, name in enumerate(quake.names):
        header, decoded = decode_tga(tmp_path / f"sky_{name}.tga")
        assert (header["type"], header["bpp"], header["top_left_origin"]) == (2, 24, False)
        expected = _srgb8(face_to_file(faces[:, 8 * k : 8 * (k + 1)], quake.transforms[k]))
        assert np.abs(decoded.astype(int) - expected).max() <= 1, name
    back = envconv.io.read(tmp_path / "sky_{face}.tga", faces="quake")
    assert back.layout.name == "cube-faces"
    np.testing.assert_allclose(back.pixels, faces, atol=0.02)


def test_tga_takes_8_bits_only(tmp_path):
    sky = envconv.EnvMap(np.ones((8, 16, 3), np.float32), "latlong")
    envconv.io.write(sky, tmp_path / "sky.exr")
    result = run_cli(["convert", tmp_path / "sky.exr", tmp_path / "sky.tga", "--to", "latlong",
                      "--bit-depth", "uint16"])  # fmt: skip
    assert result.exit_code == 2
    lines = stderr_lines(result)
    assert len(lines) == 1 and "uint8" in lines[0]
    assert not (tmp_path / "sky.tga").exists()
    ok = run_cli(["convert", tmp_path / "sky.exr", tmp_path / "sky.tga", "--to", "latlong"])
    assert ok.exit_code == 0, ok.stderr
    assert decode_tga(tmp_path / "sky.tga")[0]["bpp"] == 24
