"""DirectDraw Surface (DDS) files with the DX10 header: float RGBA textures and cube maps.

Only what envconv writes: uncompressed ``DXGI_FORMAT_R32G32B32A32_FLOAT`` (2) or
``DXGI_FORMAT_R16G16B16A16_FLOAT`` (10), one 2-D texture or one cube map, with every mip level.
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

__all__ = [
    "DDS_MAGIC",
    "DXGI_FORMAT_R32G32B32A32_FLOAT",
    "DXGI_FORMAT_R16G16B16A16_FLOAT",
    "encode_dds",
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
