"""DirectDraw Surface (DDS) files with the DX10 header: float RGBA textures and cube maps.

envconv writes uncompressed ``DXGI_FORMAT_R32G32B32A32_FLOAT`` (2) or
``DXGI_FORMAT_R16G16B16A16_FLOAT`` (10), one 2-D texture or one cube map, with every mip level;
:func:`parse_dds` reads those, ``DXGI_FORMAT_R32G32B32_FLOAT`` (6) and the legacy D3DFMT codes
of the same layouts (113 ``A16B16G16R16F``, 116 ``A32B32G32R32F``) back. Block-compressed
formats (BC6H) and volume textures are refused with their name.
The numbers below are those of Microsoft's DDS reference (learn.microsoft.com, "Direct3D DDS"):

- File: the magic ``"DDS "`` (0x20534444), a ``DDS_HEADER`` (124 bytes), a ``DDS_HEADER_DXT10``
  (20 bytes, present because ``ddspf.dwFourCC`` is ``"DX10"``), then the surfaces.
- ``DDS_HEADER`` ("DDS_HEADER structure"): ``dwFlags`` = DDSD_CAPS 0x1 | DDSD_HEIGHT 0x2 |
  DDSD_WIDTH 0x4 | DDSD_PITCH 0x8 | DDSD_PIXELFORMAT 0x1000 | DDSD_MIPMAPCOUNT 0x20000;
  ``dwPitchOrLinearSize`` is the pitch of level 0, ``(width * bits-per-pixel + 7) / 8``
  ("DDS Programming Guide", pitch of uncompressed formats); ``dwCaps`` = DDSCAPS_TEXTURE 0x1000,
  plus DDSCAPS_COMPLEX 0x8 for more than one surface and DDSCAPS_MIPMAP 0x400000 for a chain;
  ``dwCaps2`` of a cube map = DDSCAPS2_CUBEMAP 0x200 | the six POSITIVEX … NEGATIVEZ bits
  0x400, 0x800, 0x1000, 0x2000, 0x4000, 0x8000.
- ``DDS_PIXELFORMAT`` ("DDS_PIXELFORMAT structure"): ``dwSize`` 32, ``dwFlags`` DDPF_FOURCC 0x4,
  ``dwFourCC`` ``"DX10"``.
- ``DDS_HEADER_DXT10`` ("DDS_HEADER_DXT10 structure"): ``dxgiFormat``; ``resourceDimension``
  DDS_DIMENSION_TEXTURE2D (3), which also identifies cube maps; ``miscFlag``
  DDS_RESOURCE_MISC_TEXTURECUBE 0x4 for a cube; ``arraySize`` 1 (for a cube: the number of
  cubes); ``miscFlags2`` the alpha mode, DDS_ALPHA_MODE_STRAIGHT 1 or DDS_ALPHA_MODE_OPAQUE 3.
- Surfaces ("DDS File Layout for Cubic Environment Maps"): faces in the order +X, −X, +Y, −Y,
  +Z, −Z, each written with its main image followed by its mip levels; rows top to bottom,
  tightly packed, little-endian.

Cube faces are Direct3D's: the left-handed cube frame with +Y up, +Z forward and +X on the
right, each face seen from inside the cube with its first row at the top. That is exactly
envconv's GL/D3D/KTX face table (:mod:`envconv.layouts.cube`), so faces are written as stored.
"""

from __future__ import annotations

import struct

import numpy as np

from ..errors import ImageIOError
from .formats import TextureInfo

__all__ = [
    "DDS_MAGIC",
    "DXGI_FORMAT_R32G32B32A32_FLOAT",
    "DXGI_FORMAT_R16G16B16A16_FLOAT",
    "encode_dds",
    "parse_dds",
    "DDS_HEAD_BYTES",
]

DDS_MAGIC = 0x20534444  # "DDS "
DXGI_FORMAT_R32G32B32A32_FLOAT = 2
DXGI_FORMAT_R16G16B16A16_FLOAT = 10

DDSD_CAPS, DDSD_HEIGHT, DDSD_WIDTH, DDSD_PITCH = 0x1, 0x2, 0x4, 0x8
DDSD_PIXELFORMAT, DDSD_MIPMAPCOUNT = 0x1000, 0x20000
DDPF_FOURCC = 0x4
DDSCAPS_COMPLEX, DDSCAPS_TEXTURE, DDSCAPS_MIPMAP = 0x8, 0x1000, 0x400000
DDSCAPS2_CUBEMAP = 0x200
DDSCAPS2_CUBEMAP_ALLFACES = 0x400 | 0x800 | 0x1000 | 0x2000 | 0x4000 | 0x8000
DDS_DIMENSION_TEXTURE2D = 3
DDS_RESOURCE_MISC_TEXTURECUBE = 0x4
DDS_ALPHA_MODE_STRAIGHT = 1
DDS_ALPHA_MODE_OPAQUE = 3

_DXGI = {np.dtype(np.float32): DXGI_FORMAT_R32G32B32A32_FLOAT,
         np.dtype(np.float16): DXGI_FORMAT_R16G16B16A16_FLOAT}  # fmt: skip


def encode_dds(faces: list[list[np.ndarray]], cube: bool, opaque: bool) -> bytes:
    """The bytes of a DDS file holding ``faces[f][k]``: face (or the one image) f, level k.

    Parameters
    ----------
    faces : list of lists of ndarray
        Six faces in D3D order (+X, −X, +Y, −Y, +Z, −Z) for a cube map, else one image; each
        a list of its mip levels, level 0 first, every level (H_k, W_k, 4) RGBA of one dtype,
        float32 or float16, with ``H_k = max(H_0 >> k, 1)`` and ``W_k = max(W_0 >> k, 1)``.
    cube : bool
        Write a cube map (six square faces) rather than a 2-D texture.
    opaque : bool
        The alpha channel is a constant 1 added for the format (alpha mode OPAQUE), rather than
        data of its own (STRAIGHT: envconv's alpha is coverage, never premultiplied).
    """
    first = faces[0][0]
    height, width, channels = first.shape
    levels = len(faces[0])
    if channels != 4 or first.dtype not in _DXGI:
        raise ValueError("DDS surfaces must be RGBA float32 or float16")
    if cube and (len(faces) != 6 or width != height):
        raise ValueError("a DDS cube map needs six square faces")
    bytes_per_pixel = 4 * first.dtype.itemsize
    flags = DDSD_CAPS | DDSD_HEIGHT | DDSD_WIDTH | DDSD_PITCH | DDSD_PIXELFORMAT
    caps = DDSCAPS_TEXTURE
    if levels > 1:
        flags |= DDSD_MIPMAPCOUNT
        caps |= DDSCAPS_MIPMAP | DDSCAPS_COMPLEX
    caps2 = 0
    if cube:
        caps |= DDSCAPS_COMPLEX
        caps2 = DDSCAPS2_CUBEMAP | DDSCAPS2_CUBEMAP_ALLFACES
    pixel_format = struct.pack("<2I4s5I", 32, DDPF_FOURCC, b"DX10", 0, 0, 0, 0, 0)
    header = struct.pack(
        "<7I44x32s5I", 124, flags, height, width, width * bytes_per_pixel, 0, levels,
        pixel_format, caps, caps2, 0, 0, 0,
    )  # fmt: skip
    dx10 = struct.pack(
        "<5I", _DXGI[first.dtype], DDS_DIMENSION_TEXTURE2D,
        DDS_RESOURCE_MISC_TEXTURECUBE if cube else 0, 1,
        DDS_ALPHA_MODE_OPAQUE if opaque else DDS_ALPHA_MODE_STRAIGHT,
    )  # fmt: skip
    parts = [struct.pack("<I", DDS_MAGIC), header, dx10]
    for face in faces:
        for k, level in enumerate(face):
            expected = (max(height >> k, 1), max(width >> k, 1), 4)
            if level.shape != expected or level.dtype != first.dtype:
                raise ValueError(f"DDS level {k} is {level.shape} {level.dtype}, not {expected}")
            parts.append(np.ascontiguousarray(level, dtype=level.dtype.newbyteorder("<")).tobytes())
    return b"".join(parts)


#: Bytes of a DDS file's header with its DX10 extension: all :func:`parse_dds` needs.
DDS_HEAD_BYTES = 4 + 124 + 20
DXGI_FORMAT_R32G32B32_FLOAT = 6
#: (component dtype, components) of the uncompressed float formats read: DXGI codes, and the
#: legacy D3DFMT FourCC numbers of the same layouts.
_READ_DXGI = {DXGI_FORMAT_R32G32B32A32_FLOAT: ("<f4", 4), DXGI_FORMAT_R16G16B16A16_FLOAT: ("<f2", 4),
              DXGI_FORMAT_R32G32B32_FLOAT: ("<f4", 3)}  # fmt: skip
_READ_D3DFMT = {116: ("<f4", 4), 113: ("<f2", 4)}
_DXGI_NAMES = {95: "BC6H_UF16", 96: "BC6H_SF16", 98: "BC7_UNORM", 71: "BC1_UNORM", 77: "BC3_UNORM",
               28: "R8G8B8A8_UNORM", 24: "R10G10B10A2_UNORM", 26: "R11G11B10_FLOAT"}  # fmt: skip


def parse_dds(head: bytes, path: str = "DDS file") -> TextureInfo:
    """The :class:`~envconv.io.formats.TextureInfo` of a DDS file from its first
    :data:`DDS_HEAD_BYTES` bytes; ImageIOError (one line) for what is not read."""
    if len(head) < 128 or struct.unpack_from("<I", head)[0] != DDS_MAGIC:
        raise ImageIOError(f"cannot read {path}: not a DDS file")
    size, flags, height, width, _, depth, mips = struct.unpack_from("<7I", head, 4)
    pf_flags, fourcc = struct.unpack_from("<I4s", head, 80)  # DDS_PIXELFORMAT at 76
    caps, caps2 = struct.unpack_from("<2I", head, 108)
    cube = bool(caps2 & DDSCAPS2_CUBEMAP)
    opaque, offset = False, 128
    if fourcc == b"DX10":
        if len(head) < DDS_HEAD_BYTES:
            raise ImageIOError(f"cannot read {path}: its DX10 header is cut short")
        code, dimension, misc, array, alpha_mode = struct.unpack_from("<5I", head, 128)
        found = _READ_DXGI.get(code)
        what = f"DXGI format {code} ({_DXGI_NAMES.get(code, 'unknown')})"
        cube = cube or bool(misc & DDS_RESOURCE_MISC_TEXTURECUBE)
        opaque, offset = alpha_mode == DDS_ALPHA_MODE_OPAQUE, DDS_HEAD_BYTES
        if dimension != DDS_DIMENSION_TEXTURE2D:
            found, what = None, f"resource dimension {dimension} (not a 2-D texture)"
    else:
        code = struct.unpack("<I", fourcc)[0]
        found = _READ_D3DFMT.get(code) if pf_flags & DDPF_FOURCC else None
        what = f"pixel format {fourcc!r}" if pf_flags & DDPF_FOURCC else "an integer pixel format"
    if found is None:
        raise ImageIOError(f"cannot read {path}: {what} is not read by envconv; it reads "
                           "uncompressed RGBA16F, RGBA32F and RGB32F DDS files")  # fmt: skip
    if (
        cube
        and (caps2 & DDSCAPS2_CUBEMAP_ALLFACES) != DDSCAPS2_CUBEMAP_ALLFACES
        and fourcc != b"DX10"
    ):
        raise ImageIOError(f"cannot read {path}: a cube map without all six faces")
    if depth > 1 and not cube:
        raise ImageIOError(f"cannot read {path}: a volume texture (depth {depth})")
    dtype, components = found
    levels = max(int(mips), 1) if (flags & DDSD_MIPMAPCOUNT or caps & DDSCAPS_MIPMAP) else 1
    texel = np.dtype(dtype).itemsize * components
    images = {}
    for face in range(6 if cube else 1):  # each face: its main image, then its mip levels
        for k in range(levels):
            images[(face, k)] = offset
            offset += max(height >> k, 1) * max(width >> k, 1) * texel
    return TextureInfo("dds", width, height, levels, cube, dtype, components, opaque, images, {})
