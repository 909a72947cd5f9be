"""KTX 2.0 files: uncompressed float RGBA textures and cube maps with every mip level.

envconv writes ``VK_FORMAT_R32G32B32A32_SFLOAT`` (109) or ``VK_FORMAT_R16G16B16A16_SFLOAT``
(97), no supercompression, one 2-D texture or one cube map; :func:`parse_ktx2` reads those and
the RGB float formats (``R32G32B32_SFLOAT`` 106, ``R16G16B16_SFLOAT`` 90) back, of the first
array layer. Block-compressed and supercompressed files (Basis, BC6H) are refused by name.
Section names are those of the KTX File Format Specification 2.0 (Khronos, ``ktxspec.adoc``):

- "File Structure": the 12-byte identifier ``«KTX 20»\\r\\n\\x1A\\n``; nine UInt32 (vkFormat,
  typeSize, pixelWidth, pixelHeight, pixelDepth, layerCount, faceCount, levelCount,
  supercompressionScheme); the Index (dfdByteOffset, dfdByteLength, kvdByteOffset,
  kvdByteLength as UInt32, sgdByteOffset, sgdByteLength as UInt64); the Level Index, one
  (byteOffset, byteLength, uncompressedByteLength) UInt64 triple per level, level 0 first; the
  Data Format Descriptor; the Key/Value Data; then the Mip Level Array.
- "typeSize": the bytes of one component, 4 (float) or 2 (half).
- "faceCount": 6 for a cube map, faces in the order +X, −X, +Y, −Y, +Z, −Z "in a left-handed
  coordinate system with +Y up and, with the +Z face forward, +X on the right", all with
  orientation ``rd`` (first texel top-left, rows downward); "Cubemap Orientation" ties this to
  the Vulkan and OpenGL cube samplers. That is envconv's GL/D3D/KTX face table
  (:mod:`envconv.layouts.cube`), so faces are written as stored. pixelDepth and layerCount are
  0 ("Texture Type").
- "Mip Level Array" / "levelCount": levels are stored from the smallest to the largest, each
  preceded by ``mipPadding`` to a multiple of lcm(texel block size, 4): 16 bytes for RGBA32F,
  8 for RGBA16F. Within a level the faces follow each other ("levelImages"), rows tightly
  packed ("Packing").
- "Data Format Descriptor": one Khronos basic descriptor block (Khronos Data Format
  Specification 1.4, chapter "Khronos Basic Data Format Descriptor Block"): colour model
  RGBSDA (1), primaries BT709 (1), transfer LINEAR (1), flags ALPHA_STRAIGHT (0),
  texelBlockDimension 0 (1 × 1 × 1 × 1), bytesPlane0 = bytes per texel, one sample per channel
  (R 0, G 1, B 2, A 15) with qualifiers FLOAT | SIGNED (0x80 | 0x40) and sampleLower/Upper
  the float bits of −1.0 and 1.0, as the Khronos dfdutils' ``createDFDUnpacked`` writes them.
- "Key/Value Data": ``KTXorientation`` = ``rd`` and ``KTXwriter``, sorted by key, each padded
  to 4 bytes.
"""

from __future__ import annotations

import struct

import numpy as np

from ..errors import ImageIOError
from .formats import TextureInfo

__all__ = [
    "KTX2_IDENTIFIER",
    "VK_FORMAT_R32G32B32A32_SFLOAT",
    "VK_FORMAT_R16G16B16A16_SFLOAT",
    "encode_ktx2",
    "basic_dfd",
    "parse_ktx2",
    "ktx2_head_bytes",
]

KTX2_IDENTIFIER = bytes([0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A])
VK_FORMAT_R32G32B32A32_SFLOAT = 109
VK_FORMAT_R16G16B16A16_SFLOAT = 97

_VK = {np.dtype(np.float32): VK_FORMAT_R32G32B32A32_SFLOAT,
       np.dtype(np.float16): VK_FORMAT_R16G16B16A16_SFLOAT}  # fmt: skip
KHR_DF_MODEL_RGBSDA, KHR_DF_PRIMARIES_BT709, KHR_DF_TRANSFER_LINEAR = 1, 1, 1
KHR_DF_VERSIONNUMBER_1_3 = 2
KHR_DF_SAMPLE_DATATYPE_FLOAT, KHR_DF_SAMPLE_DATATYPE_SIGNED = 0x80, 0x40
_CHANNEL_IDS = (0, 1, 2, 15)  # KHR_DF_CHANNEL_RGBSDA_RED, GREEN, BLUE, ALPHA
_FLOAT_MINUS_ONE, _FLOAT_ONE = 0xBF800000, 0x3F800000


def basic_dfd(component_bytes: int) -> bytes:
    """The Data Format Descriptor (dfdTotalSize and one basic block) of float RGBA texels."""
    samples = b"".join(
        struct.pack(
            "<IIII",
            (8 * component_bytes * i)
            | ((8 * component_bytes - 1) << 16)
            | ((channel | KHR_DF_SAMPLE_DATATYPE_FLOAT | KHR_DF_SAMPLE_DATATYPE_SIGNED) << 24),
            0,
            _FLOAT_MINUS_ONE,
            _FLOAT_ONE,
        )
        for i, channel in enumerate(_CHANNEL_IDS)
    )
    block_size = 24 + len(samples)
    block = struct.pack(
        "<IIIIII",
        0,  # vendorId KHRONOS (17 bits), descriptorType BASICFORMAT (15 bits)
        KHR_DF_VERSIONNUMBER_1_3 | (block_size << 16),
        KHR_DF_MODEL_RGBSDA | (KHR_DF_PRIMARIES_BT709 << 8) | (KHR_DF_TRANSFER_LINEAR << 16),
        0,  # texelBlockDimension0..3: one texel
        4 * component_bytes,  # bytesPlane0; bytesPlane1..3 = 0
        0,  # bytesPlane4..7
    )
    return struct.pack("<I", 4 + block_size) + block + samples


def _key_values(pairs: dict[str, bytes]) -> bytes:
    out = []
    for key in sorted(pairs):
        entry = key.encode("utf-8") + b"\0" + pairs[key]
        out.append(struct.pack("<I", len(entry)) + entry + b"\0" * (-len(entry) % 4))
    return b"".join(out)


def encode_ktx2(faces: list[list[np.ndarray]], cube: bool, writer: str,
                extra: dict[str, bytes] | None = None) -> bytes:  # fmt: skip
    """The bytes of a KTX2 file holding ``faces[f][k]``: face (or the one image) f, level k.

    Parameters
    ----------
    faces : list of lists of ndarray
        Six faces in KTX order (+X, −X, +Y, −Y, +Z, −Z) for a cube map, else one image; each
        a list of its mip levels, level 0 first, every level (H_k, W_k, 4) RGBA of one dtype,
        float32 or float16, with ``H_k = max(H_0 >> k, 1)`` and ``W_k = max(W_0 >> k, 1)``.
    cube : bool
        Write a cube map (faceCount 6, square faces) rather than a 2-D texture.
    writer : str
        The ``KTXwriter`` value, e.g. ``"envconv 0.1.0"``.
    extra : dict, optional
        More key/value pairs (key → value bytes); keys must not start with ``KTX``.
    """
    first = faces[0][0]
    height, width, channels = first.shape
    levels = len(faces[0])
    if channels != 4 or first.dtype not in _VK:
        raise ValueError("KTX2 images must be RGBA float32 or float16")
    if cube and (len(faces) != 6 or width != height):
        raise ValueError("a KTX2 cube map needs six square faces")
    pairs = {"KTXorientation": b"rd\0", "KTXwriter": writer.encode("utf-8") + b"\0"}
    for key, value in (extra or {}).items():
        if key.upper().startswith("KTX"):
            raise ValueError(f"KTX2 key {key!r} is reserved")
        pairs[key] = value
    dfd = basic_dfd(first.dtype.itemsize)
    kvd = _key_values(pairs)
    dfd_offset = 12 + 9 * 4 + 4 * 4 + 2 * 8 + levels * 3 * 8
    kvd_offset = dfd_offset + len(dfd)
    align = int(np.lcm(4 * first.dtype.itemsize, 4))
    level_bytes = []
    for k in range(levels):
        expected = (max(height >> k, 1), max(width >> k, 1), 4)
        data = []
        for face in faces:
            level = face[k]
            if level.shape != expected or level.dtype != first.dtype:
                raise ValueError(f"KTX2 level {k} is {level.shape} {level.dtype}, not {expected}")
            data.append(np.ascontiguousarray(level, dtype=level.dtype.newbyteorder("<")).tobytes())
        level_bytes.append(b"".join(data))
    body, index, offset = [], [None] * levels, kvd_offset + len(kvd)
    for k in reversed(range(levels)):  # the smallest level first
        pad = -offset % align
        body.append(b"\0" * pad)
        offset += pad
        index[k] = struct.pack("<3Q", offset, len(level_bytes[k]), len(level_bytes[k]))
        body.append(level_bytes[k])
        offset += len(level_bytes[k])
    head = KTX2_IDENTIFIER + struct.pack(
        "<9I4I2Q", _VK[first.dtype], first.dtype.itemsize, width, height, 0, 0,
        6 if cube else 1, levels, 0, dfd_offset, len(dfd), kvd_offset, len(kvd), 0, 0,
    )  # fmt: skip
    return b"".join([head, *index, dfd, kvd, *body])


#: (component dtype, components) of the float formats read, by vkFormat.
_READ_VK = {VK_FORMAT_R32G32B32A32_SFLOAT: ("<f4", 4), VK_FORMAT_R16G16B16A16_SFLOAT: ("<f2", 4),
            106: ("<f4", 3), 90: ("<f2", 3)}  # fmt: skip
_HEAD = 12 + 9 * 4 + 4 * 4 + 2 * 8  # identifier, header, index: the level index follows


def ktx2_head_bytes(first: bytes) -> int:
    """How many bytes :func:`parse_ktx2` needs (up to the end of the Key/Value Data), from
    the file's first 80 bytes."""
    levels = max(struct.unpack_from("<I", first, 12 + 7 * 4)[0], 1)
    kvd_offset, kvd_length = struct.unpack_from("<2I", first, 12 + 9 * 4 + 8)
    return max(_HEAD + 24 * levels, kvd_offset + kvd_length)


def parse_ktx2(head: bytes, path: str = "KTX2 file") -> TextureInfo:
    """The :class:`~envconv.io.formats.TextureInfo` of a KTX2 file from its first
    :func:`ktx2_head_bytes` bytes; ImageIOError (one line) for what is not read."""
    if len(head) < _HEAD or head[:12] != KTX2_IDENTIFIER:
        raise ImageIOError(f"cannot read {path}: not a KTX2 file")
    vk, _, width, height, depth, layers, faces, levels, scheme = struct.unpack_from("<9I", head, 12)
    found = _READ_VK.get(vk)
    if found is None or scheme:
        what = f"supercompression scheme {scheme}" if scheme else f"vkFormat {vk}"
        raise ImageIOError(f"cannot read {path}: {what} is not read by envconv; it reads "
                           "uncompressed RGBA and RGB float KTX2 files")  # fmt: skip
    if depth > 1 or faces not in (1, 6) or height == 0:
        raise ImageIOError(f"cannot read {path}: a {'3-D' if depth > 1 else '1-D'} texture or "
                           f"{faces} faces, not a 2-D texture or a cube map")  # fmt: skip
    levels = max(levels, 1)
    dtype, components = found
    texel = np.dtype(dtype).itemsize * components
    images = {}
    for k in range(levels):  # a level: each layer's faces in turn; layer 0 is read
        start = struct.unpack_from("<Q", head, _HEAD + 24 * k)[0]
        size = max(height >> k, 1) * max(width >> k, 1) * texel
        for face in range(faces):
            images[(face, k)] = start + face * size
    metadata = _read_key_values(head, *struct.unpack_from("<2I", head, 12 + 9 * 4 + 8))
    opaque = metadata.get("envconv:channels", "RGBA") != "RGBA" and components == 4
    flip = metadata.get("KTXorientation", "rd")[1:2] == "u"
    return TextureInfo("ktx2", width, height, levels, faces == 6, dtype, components, opaque,
                       images, metadata, flip)  # fmt: skip


def _read_key_values(data: bytes, offset: int, length: int) -> dict[str, str]:
    """The Key/Value Data as text (values that are not UTF-8 text are left out)."""
    pairs, at, end = {}, offset, offset + length
    while at + 4 <= end:
        size = struct.unpack_from("<I", data, at)[0]
        entry = data[at + 4 : at + 4 + size]
        at += 4 + size + (-size % 4)
        key, _, value = entry.partition(b"\0")
        try:
            pairs[key.decode("utf-8")] = value.rstrip(b"\0").decode("utf-8")
        except UnicodeDecodeError:
            continue
    return pairs
