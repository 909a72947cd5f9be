"""DDS and KTX2 files (envconv.io.textures, envconv.io.dds, envconv.io.ktx2), read by independent readers.

parse-dds and ktx-parse (npm, tests/node) locate every image from the header alone; the bytes
they find must be the in-memory chain, bit for bit, and the faces must be where the D3D/Vulkan
cube tables put them. The header fields of the RGBA16F DDS (which parse-dds refuses) are
checked against Microsoft's tables, written out here.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest
from conftest import run_cli, stderr_lines
from node_readers import read_container

import envconv
from envconv.errors import LayoutError, UsageError

N = 16
LEVELS = 5  # 16, 8, 4, 2, 1


def _direction_latlong(height=128):
    """A lat-long whose RGB is its own world direction (pixel centres)."""
    v = (np.arange(height) + 0.5) / height
    u = (np.arange(2 * height) + 0.5) / (2 * height)
    lon = 2 * np.pi * (0.5 - u)[None, :]
    lat = np.pi * (0.5 - v)[:, None]
    d = np.stack(np.broadcast_arrays(np.sin(lon) * np.cos(lat), np.sin(lat),
                                     np.cos(lon) * np.cos(lat)), -1)  # fmt: skip
    return envconv.EnvMap(d.astype(np.float32), "latlong")


@pytest.fixture(scope="module")
def chain():
    """A cube-faces map with a full chain: RGB = world direction, so orientation shows."""
    return envconv.convert(_direction_latlong(), "cube-faces", size=N, mips=True, samples=4)


#: Cell (column, row, half turns) of faces +X_c … −Z_c, as docs/geometry.md places them.
CELLS = {
    "cube-faces": [(f, 0, 0) for f in range(6)],
    "cube-vstrip": [(0, f, 0) for f in range(6)],
    "cube-vcross": [(2, 1, 0), (0, 1, 0), (1, 0, 0), (1, 2, 0), (1, 1, 0), (1, 3, 2)],
    "cube-hcross": [(2, 1, 0), (0, 1, 0), (1, 0, 0), (1, 2, 0), (1, 1, 0), (3, 1, 0)],
}


def _faces(levels, layout="cube-faces"):
    """faces[f][k]: face f of level k, cut from the layout's image by docs/geometry.md's cell table,
    RGBA float32 (alpha 1 added)."""
    out = []
    for col, row, turns in CELLS[layout]:
        faces = []
        for k in range(LEVELS):
            n = N >> k
            rgb = levels[k][row * n : (row + 1) * n, col * n : (col + 1) * n, :3]
            rgb = np.rot90(rgb, turns)
            faces.append(np.concatenate([rgb, np.ones_like(rgb[:, :, :1])], axis=2))
        out.append(faces)
    return out


def _d3d_direction(face, size):
    """World direction of every texel of a D3D/Vulkan/KTX cube face (t downward).

    The cube-map face selection table (Vulkan spec "Cube Map Face Selection", OpenGL 4.6
    table 8.19): for major axis +X, (sc, tc, ma) = (−rz, −ry, rx); −X: (rz, −ry, −rx);
    +Y: (rx, rz, ry); −Y: (rx, −rz, −ry); +Z: (rx, −ry, rz); −Z: (−rx, −ry, −rz), with
    s = (sc/|ma| + 1)/2, t = (tc/|ma| + 1)/2. Inverted for (s, t) at texel centres. The cube
    frame is left-handed (+X right, +Y up, +Z forward); the world frame is the same with x
    negated (KTX2 spec, "Cubemap Orientation"; envconv's docs/geometry.md).
    """
    s = 2 * (np.arange(size) + 0.5) / size - 1
    sc, tc = np.meshgrid(s, s)  # tc runs down the rows
    one = np.ones_like(sc)
    r = {
        0: (one, -tc, -sc), 1: (-one, -tc, sc), 2: (sc, one, tc),
        3: (sc, -one, -tc), 4: (sc, -tc, one), 5: (-sc, -tc, -one),
    }[face]  # fmt: skip
    c = np.stack(r, -1)
    c /= np.linalg.norm(c, axis=-1, keepdims=True)
    return c * np.array([-1.0, 1.0, 1.0])


def _unpack(data, shape, dtype=np.float32):
    return np.frombuffer(data, dtype=np.dtype(dtype).newbyteorder("<")).reshape(shape)


@pytest.mark.parametrize("layout", ["cube-faces", "cube-vcross", "cube-hcross", "cube-vstrip"])
def test_dds_faces_read_by_parse_dds(tmp_path, layout):
    source = _direction_latlong()
    cube = envconv.convert(source, layout, size=N, mips=True, samples=4)
    path = tmp_path / "sky.dds"
    assert envconv.write(cube, path) == [str(path)]
    info, data = read_container(path, tmp_path / "out.bin")
    assert info["format"] == "rgba32f" and info["cubemap"] is True
    assert info["shape"] == [N, N] and len(info["images"]) == 6 * LEVELS
    expected = b"".join(face.tobytes() for faces in _faces(cube.levels, layout) for face in faces)
    assert data == expected
    offset = 0
    for face in range(6):
        for k in range(LEVELS):
            size = N >> k
            image = _unpack(data[offset : offset + size * size * 16], (size, size, 4))
            offset += size * size * 16
            if size >= 4:
                got = image[:, :, :3] / np.linalg.norm(image[:, :, :3], axis=-1, keepdims=True)
                cos = (got * _d3d_direction(face, size)).sum(-1)
                assert cos.min() > np.cos(0.5 * np.pi / size), (face, k)
            np.testing.assert_array_equal(image[:, :, 3], 1.0)


def test_ktx2_read_by_ktx_parse(tmp_path, chain):
    path = tmp_path / "sky.ktx2"
    envconv.write(chain, path)
    info, data = read_container(path, tmp_path / "out.bin")
    assert (info["vkFormat"], info["typeSize"]) == (109, 4)  # VK_FORMAT_R32G32B32A32_SFLOAT
    assert (info["pixelWidth"], info["pixelHeight"], info["pixelDepth"]) == (N, N, 0)
    assert (info["layerCount"], info["faceCount"], info["levelCount"]) == (0, 6, LEVELS)
    assert info["supercompressionScheme"] == 0
    assert info["keyValue"]["KTXorientation"] == "rd"
    assert info["keyValue"]["KTXwriter"].startswith("envconv ")
    dfd = info["dfd"]
    assert (dfd["colorModel"], dfd["colorPrimaries"], dfd["transferFunction"]) == (1, 1, 1)
    assert dfd["bytesPlane"][0] == 16
    assert [s["channelType"] for s in dfd["samples"]] == [0xC0, 0xC1, 0xC2, 0xCF]
    assert [(s["bitOffset"], s["bitLength"]) for s in dfd["samples"]] == [
        (0, 31), (32, 31), (64, 31), (96, 31)]  # fmt: skip
    faces = _faces(chain.levels)
    expected = b"".join(faces[f][k].tobytes() for k in range(LEVELS) for f in range(6))
    assert data == expected
    assert [lv["byteLength"] for lv in info["levels"]] == [6 * 16 * (N >> k) ** 2
                                                           for k in range(LEVELS)]  # fmt: skip


def test_ktx2_half_equals_float_rounded(tmp_path, chain):
    envconv.write(chain, tmp_path / "f.ktx2")
    envconv.write(chain, tmp_path / "h.ktx2", bit_depth="half")
    _, full = read_container(tmp_path / "f.ktx2", tmp_path / "f.bin")
    info, half = read_container(tmp_path / "h.ktx2", tmp_path / "h.bin")
    assert (info["vkFormat"], info["typeSize"], info["dfd"]["bytesPlane"][0]) == (97, 2, 8)
    assert [(s["bitOffset"], s["bitLength"]) for s in info["dfd"]["samples"]] == [
        (0, 15), (16, 15), (32, 15), (48, 15)]  # fmt: skip
    as_half = np.frombuffer(full, "<f4").astype(np.float16)
    np.testing.assert_array_equal(np.frombuffer(half, "<f2"), as_half)


def test_dds_half_header_matches_the_spec(tmp_path, chain):
    """RGBA16F: parse-dds refuses DXGI format 10, so every header field is checked here
    against Microsoft's tables ("DDS_HEADER", "DDS_PIXELFORMAT", "DDS_HEADER_DXT10"), and the
    data against the RGBA32F file that parse-dds reads."""
    envconv.write(chain, tmp_path / "f.dds")
    envconv.write(chain, tmp_path / "h.dds", bit_depth="half")
    info, full = read_container(tmp_path / "f.dds", tmp_path / "f.bin")
    raw = (tmp_path / "h.dds").read_bytes()
    assert raw[:4] == b"DDS "
    (size, flags, height, width, pitch, depth, mips) = struct.unpack_from("<7I", raw, 4)
    assert size == 124
    # DDSD_CAPS | DDSD_HEIGHT | DDSD_WIDTH | DDSD_PITCH | DDSD_PIXELFORMAT | DDSD_MIPMAPCOUNT
    assert flags == 0x1 | 0x2 | 0x4 | 0x8 | 0x1000 | 0x20000
    assert (height, width, depth, mips) == (N, N, 0, LEVELS)
    assert pitch == (width * 64 + 7) // 8  # (width * bits-per-pixel + 7) / 8
    assert struct.unpack_from("<11I", raw, 32) == (0,) * 11
    pf_size, pf_flags, fourcc, *masks = struct.unpack_from("<2I4s5I", raw, 76)
    assert (pf_size, pf_flags, fourcc, masks) == (32, 0x4, b"DX10", [0] * 5)  # DDPF_FOURCC
    caps, caps2, caps3, caps4, reserved2 = struct.unpack_from("<5I", raw, 108)
    assert caps == 0x8 | 0x1000 | 0x400000  # COMPLEX | TEXTURE | MIPMAP
    assert caps2 == 0x200 | 0x400 | 0x800 | 0x1000 | 0x2000 | 0x4000 | 0x8000  # CUBEMAP, 6 faces
    assert (caps3, caps4, reserved2) == (0, 0, 0)
    dxgi, dimension, misc, array_size, misc2 = struct.unpack_from("<5I", raw, 128)
    assert dxgi == 10  # DXGI_FORMAT_R16G16B16A16_FLOAT
    assert dimension == 3  # DDS_DIMENSION_TEXTURE2D
    assert misc == 0x4 and array_size == 1  # DDS_RESOURCE_MISC_TEXTURECUBE, one cube
    assert misc2 == 3  # DDS_ALPHA_MODE_OPAQUE: the alpha was added as 1
    assert raw[148:] == np.frombuffer(full, "<f4").astype("<f2").tobytes()
    assert len(full) == sum(im["length"] for im in info["images"])


def test_ktx2_latlong_is_a_2d_texture_with_alpha(tmp_path):
    sky = envconv.convert(_direction_latlong(), "latlong", size=16, mips=True, alpha=True)
    envconv.write(sky, tmp_path / "ll.ktx2")
    info, data = read_container(tmp_path / "ll.ktx2", tmp_path / "ll.bin")
    assert (info["pixelWidth"], info["pixelHeight"], info["faceCount"]) == (32, 16, 1)
    assert info["levelCount"] == 6
    assert data == b"".join(level.tobytes() for level in sky.levels)
    assert info["keyValue"]["envconv:layout"].rstrip("\0") == "latlong"


def test_dds_latlong_header(tmp_path):
    sky = envconv.convert(_direction_latlong(), "latlong", size=16, mips=True)
    envconv.write(sky, tmp_path / "ll.dds")
    raw = (tmp_path / "ll.dds").read_bytes()
    height, width = struct.unpack_from("<2I", raw, 12)
    assert (height, width) == (16, 32)
    assert struct.unpack_from("<2I", raw, 108)[1] == 0  # no cube flags
    assert struct.unpack_from("<3I", raw, 128) == (2, 3, 0)
    expected = b"".join(np.concatenate([lv, np.ones_like(lv[:, :, :1])], 2).tobytes()
                        for lv in sky.levels)  # fmt: skip
    assert raw[148:] == expected


def test_guarded_cube_and_face_paths_are_refused(tmp_path, chain):
    guarded = envconv.convert(_direction_latlong(), "cube-hstrip", size=N, guard=2)
    with pytest.raises(UsageError, match="guard"):  # two arguments contradict: exit 2
        envconv.write(guarded, tmp_path / "g.dds")
    with pytest.raises(LayoutError, match="drop"):
        envconv.write(chain, tmp_path / "c_{face}.ktx2")
    assert not list(tmp_path.iterdir())


def test_cli_writes_a_cube_dds(tmp_path):
    src = tmp_path / "in.exr"
    envconv.write(_direction_latlong(64), src)
    out = tmp_path / "sky.dds"
    result = run_cli(["convert", src, out, "--to", "cube-faces", "--size", "8", "--mips"])
    assert result.exit_code == 0, result.stderr
    assert not stderr_lines(result)
    info, _ = read_container(out, tmp_path / "o.bin")
    assert info["cubemap"] and info["shape"] == [8, 8] and len(info["images"]) == 6 * 4


# --- reading them back (envconv.io.dds.parse_dds, envconv.io.ktx2.parse_ktx2, io.textures) ---
# Truth: the images the independent readers locate in the file (their bytes, in their order),
# the chain in memory that was written, and CONVENTIONS' cell table (CELLS above).


def _as_faces(env, layout):
    """faces[f] of a map read back (RGB), cut by the cell table of its layout."""
    n = env.size
    out = []
    for col, row, turns in CELLS[layout]:
        out.append(np.rot90(env.pixels[row * n : (row + 1) * n, col * n : (col + 1) * n], turns))
    return out


CELLS["cube-hstrip"] = CELLS["cube-faces"]


@pytest.mark.parametrize("ext", ["dds", "ktx2"])
@pytest.mark.parametrize("depth", ["float", "half"])
def test_cube_files_read_back_as_the_independent_readers_see_them(tmp_path, chain, ext, depth):
    """Every level of a cube file read back by envconv holds, face by face, the images
    parse-dds / ktx-parse find in the file (float), or the written chain rounded to half."""
    path = tmp_path / f"sky.{ext}"
    envconv.write(chain, path, bit_depth=depth)
    stored = _faces(chain.levels)
    if depth == "float":  # parse-dds refuses RGBA16F; ktx-parse reads both
        _, data = read_container(path, tmp_path / "out.bin")
        order = ([(f, k) for f in range(6) for k in range(LEVELS)] if ext == "dds" else
                 [(f, k) for k in range(LEVELS) for f in range(6)])  # fmt: skip
        at = 0
        for f, k in order:
            n = N >> k
            stored[f][k] = _unpack(data[at : at + n * n * 16], (n, n, 4))
            at += n * n * 16
    for k in range(LEVELS):
        env = envconv.read(path, level=k)
        assert env.layout.name == "cube-hstrip" and env.size == N >> k  # no tag: faces in order
        assert env.channels == ("R", "G", "B") and env.pixel_type == depth  # the added A dropped
        for f, face in enumerate(_as_faces(env, "cube-hstrip")):
            expected = stored[f][k][:, :, :3].astype(np.float16 if depth == "half" else np.float32)
            np.testing.assert_array_equal(face, expected.astype(np.float32), err_msg=f"{f} {k}")


@pytest.mark.parametrize("layout", ["cube-vcross", "cube-hcross", "cube-vstrip"])
def test_a_ktx2_cube_reads_back_in_the_layout_it_was_written_from(tmp_path, layout):
    cube = envconv.convert(_direction_latlong(), layout, size=N, mips=True, samples=4)
    envconv.write(cube, tmp_path / "sky.ktx2")
    for k in (0, 2, LEVELS - 1):
        env = envconv.read(tmp_path / "sky.ktx2", level=k)
        assert env.layout.name == layout and env.size == N >> k
        cells = np.zeros(cube.levels[k].shape[:2], bool)  # the cells that hold faces
        n = N >> k
        for col, row, _ in CELLS[layout]:
            cells[row * n : (row + 1) * n, col * n : (col + 1) * n] = True
        np.testing.assert_array_equal(env.pixels[cells], cube.levels[k][cells])
        np.testing.assert_array_equal(env.pixels[~cells], 0)


def test_a_2d_ktx2_keeps_its_alpha_guard_and_layout(tmp_path):
    sky = envconv.convert(_direction_latlong(), "paraboloid", size=16, alpha=True, guard=2)
    envconv.write(sky, tmp_path / "p.ktx2")
    back = envconv.read(tmp_path / "p.ktx2")
    assert (back.layout.name, back.guard, back.size) == ("paraboloid", 2, 16)
    assert back.channels == ("R", "G", "B", "A")
    np.testing.assert_array_equal(back.pixels, sky.pixels)


def _legacy_dds(path, pixels):
    """An RGBA32F 2-D DDS with the legacy header (FourCC 116, D3DFMT_A32B32G32R32F, no DX10
    extension) as Microsoft's "DDS_HEADER" page lays it out, made here without envconv."""
    height, width = pixels.shape[:2]
    pixel_format = struct.pack("<2I4s5I", 32, 0x4, struct.pack("<I", 116), 0, 0, 0, 0, 0)
    header = struct.pack("<7I44x32s5I", 124, 0x1 | 0x2 | 0x4 | 0x1000, height, width, 0, 0, 0,
                         pixel_format, 0x1000, 0, 0, 0, 0)  # fmt: skip
    path.write_bytes(b"DDS " + header + pixels.astype("<f4").tobytes())


def test_a_legacy_float_dds_reads(tmp_path):
    pixels = np.random.default_rng(4).uniform(0, 3, (8, 16, 4)).astype(np.float32)
    _legacy_dds(tmp_path / "old.dds", pixels)
    env = envconv.read(tmp_path / "old.dds")
    assert env.layout.name == "latlong" and env.channels == ("R", "G", "B", "A")
    np.testing.assert_array_equal(env.pixels, pixels)


@pytest.mark.parametrize("case, message", [
    ("bc6h", "DXGI format 95 (BC6H_UF16) is not read"), ("cut", "cut short"),
    ("ktx-basis", "supercompression scheme 1"),
])  # fmt: skip
def test_texture_files_envconv_does_not_read_fail_in_one_line(tmp_path, chain, case, message):
    if case == "ktx-basis":
        path = tmp_path / "sky.ktx2"
        envconv.write(chain, path)
        data = bytearray(path.read_bytes())
        data[12 + 8 * 4 : 12 + 9 * 4] = struct.pack("<I", 1)  # supercompressionScheme
    else:
        path = tmp_path / "sky.dds"
        envconv.write(chain, path)
        data = bytearray(path.read_bytes())
        if case == "bc6h":
            data[128:132] = struct.pack("<I", 95)
        else:
            del data[len(data) // 2 :]
    path.write_bytes(bytes(data))
    result = run_cli(["convert", path, tmp_path / "o.exr", "--to", "latlong", "--size", "8"])
    assert result.exit_code == 1 and result.stdout == ""
    (line,) = stderr_lines(result)
    assert line.startswith("envconv: error: cannot read") and message in line, line


def test_info_and_convert_read_the_files_envconv_writes(tmp_path, chain):
    """'Unsupported DXGI format' was all info and convert said of an envconv DDS."""
    import json

    envconv.write(chain, tmp_path / "sky.dds", bit_depth="half")
    result = run_cli(["info", tmp_path / "sky.dds", "--json"])
    assert result.exit_code == 0, result.stderr
    record = json.loads(result.stdout)
    assert (record["layout"], record["size"], record["pixel_type"]) == ("cube-hstrip", N, "half")
    assert record["levels"] == [[6 * (N >> k), N >> k] for k in range(LEVELS)]
    assert record["metadata"]["envconv:container"].startswith("DDS cube map, 6 faces of 16x16")
    out = tmp_path / "back.exr"
    result = run_cli(["convert", tmp_path / "sky.dds", out, "--to", "cube-hstrip", "--size",
                      str(N), "--samples", "1"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    back = envconv.read(out)  # the same face grid: each texel read at its own centre
    half = [f[0][:, :, :3].astype(np.float16).astype(np.float32) for f in _faces(chain.levels)]
    for face, expected in zip(_as_faces(back, "cube-hstrip"), half, strict=True):
        np.testing.assert_allclose(face, expected, atol=1e-6)
