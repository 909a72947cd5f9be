"""Engine-ready texture files: DDS and KTX2 cube maps (or 2-D textures) with their mip chains.

envconv writes and reads these containers itself (:mod:`envconv.io.dds`,
:mod:`envconv.io.ktx2`): no maintained Python library writes float DDS or KTX2, and
OpenImageIO reads neither float DDS nor KTX2. A map in a GL-table cube layout (cube-faces,
cube-hstrip, cube-vstrip, cube-hcross, cube-vcross) is written as a cube map: its six faces,
in the face order and orientation both formats define, which are the layouts' own (the
cross's rotated −Z_c cell is turned back). Any other single-file layout is written as a 2-D
texture of the whole image. Pixels are RGBA: one channel is repeated into RGB, and a missing
alpha is written as 1 and flagged opaque (DDS: alpha mode OPAQUE; KTX2: ``envconv:channels``).

Reading (:func:`texture_info`, :func:`texture_pixels`) gives the map back: a cube map in the
layout its KTX2 ``envconv:layout`` names when that is a single-file cube layout, else as a
``cube-hstrip`` (the six faces side by side in face order, as stored); a 2-D texture as its
image, placed by its tags (KTX2) or its aspect. An added alpha is dropped again.
"""

from __future__ import annotations

import logging

import numpy as np

from ..errors import ImageIOError
from ..layouts import Layout, get_layout
from ..layouts.base import FAMILY_CUBE_GL
from .dds import DDS_HEAD_BYTES, DDS_MAGIC, parse_dds
from .formats import CONTAINER_FORMATS, TextureInfo  # the table lives with the other formats'
from .ktx2 import KTX2_IDENTIFIER, ktx2_head_bytes, parse_ktx2
from .write_plan import container_levels

__all__ = ["CONTAINER_FORMATS", "cube_faces", "texture_images", "encode_texture", "texture_info",
           "texture_layout", "texture_size", "texture_pixels", "texture_channels"]  # fmt: skip

log = logging.getLogger(__name__)


def cube_faces(layout: Layout, pixels: np.ndarray) -> list[np.ndarray]:
    """The six faces of one level of a GL-table cube layout (no guard ring), in face order
    +X_c, −X_c, +Y_c, −Y_c, +Z_c, −Z_c, each (n, n, C) with its first row at the top."""
    height, width = pixels.shape[:2]
    cw, ch = width // layout.columns, height // layout.rows
    faces: list[np.ndarray | None] = [None] * 6
    for cell in layout.cells:
        block = pixels[cell.row * ch : (cell.row + 1) * ch, cell.col * cw : (cell.col + 1) * cw]
        faces[cell.face] = np.rot90(block, 2) if cell.turns == 2 else block
    return [np.ascontiguousarray(face) for face in faces]


def _rgba(pixels: np.ndarray, alpha_index: int | None) -> np.ndarray:
    """(H, W, 4) RGBA of ``pixels``, in its dtype: Y is repeated, a missing alpha is 1."""
    channels = pixels.shape[2]
    if alpha_index is not None:
        colour = [i for i in range(channels) if i != alpha_index][:3]
        alpha = pixels[:, :, alpha_index : alpha_index + 1]
    else:
        colour = list(range(min(channels, 3)))
        alpha = np.ones(pixels.shape[:2] + (1,), pixels.dtype)
    rgb = pixels[:, :, colour]
    if rgb.shape[2] == 1:
        rgb = np.repeat(rgb, 3, axis=2)
    elif rgb.shape[2] == 2:
        rgb = np.concatenate([rgb, np.zeros_like(rgb[:, :, :1])], axis=2)
    return np.ascontiguousarray(np.concatenate([rgb, alpha], axis=2))


def texture_images(layout: Layout, levels: list[np.ndarray],
                   alpha_index: int | None) -> tuple[list[list[np.ndarray]], bool]:  # fmt: skip
    """(images[f][k] RGBA, cube) for a container: six faces for a cube layout, else one image.

    ``levels`` are the map's mip levels (level 0 first) as they are to be stored; the writer
    has refused what a container cannot hold (:func:`envconv.io.write_plan.check_write`).
    """
    cube = layout.family == FAMILY_CUBE_GL
    if cube:
        levels = _whole_face_levels(layout, levels)
        per_level = [cube_faces(layout, level) for level in levels]
        faces = [[_rgba(per_level[k][f], alpha_index) for k in range(len(levels))]
                 for f in range(6)]  # fmt: skip
        return faces, True
    return [[_rgba(level, alpha_index) for level in levels]], False


def _whole_face_levels(layout: Layout, levels: list[np.ndarray]) -> list[np.ndarray]:
    """The leading levels whose cells are whole faces of ``max(n >> k, 1)`` texels.

    A strip or cross chain goes on below 1-texel faces (its image keeps halving), and when n
    is not a power of two its lower levels cut faces into fractions of a texel; neither can be
    stored as cube faces.
    """
    n = levels[0].shape[0] // layout.rows
    kept = levels[: container_levels(layout, n, len(levels))]
    if n >> (len(kept) - 1) > 1 and len(kept) < len(levels):
        log.warning(
            "faces of %d texels halve into whole texels for %d levels only; the cube "
            "file holds those (use a power-of-two size for a full chain)",
            n,
            len(kept),
        )
    return kept


def encode_texture(fmt: str, images: list[list[np.ndarray]], cube: bool, opaque: bool,
                   writer: str, extra: dict[str, str] | None = None) -> bytes:  # fmt: skip
    """The bytes of a ``fmt`` (``"dds"`` or ``"ktx2"``) file holding ``images``.

    ``extra`` key/value text goes into a KTX2 file's Key/Value Data (DDS has no place for it).
    """
    if fmt == "dds":
        from .dds import encode_dds

        return encode_dds(images, cube, opaque)
    from .ktx2 import encode_ktx2

    pairs = {key: value.encode("utf-8") + b"\0" for key, value in (extra or {}).items()}
    return encode_ktx2(images, cube, writer, pairs)


def texture_info(path: str) -> TextureInfo | None:
    """The :class:`~envconv.io.formats.TextureInfo` of a DDS or KTX2 file (known by its first
    bytes, whatever its extension), None for any other file (or none)."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(80)
            if head[:4] == DDS_MAGIC.to_bytes(4, "little"):
                return parse_dds(head + handle.read(DDS_HEAD_BYTES - len(head)), path)
            if head[:12] == KTX2_IDENTIFIER and len(head) == 80:
                need = ktx2_head_bytes(head)
                if need > 1 << 24:
                    raise ImageIOError(f"cannot read {path}: its KTX2 header claims {need} bytes")
                return parse_ktx2(head + handle.read(need - len(head)), path)
    except OSError:
        return None  # missing, a folder, unreadable: the image readers say which
    return None


def texture_layout(info: TextureInfo) -> tuple[str | None, dict]:
    """(layout to place the image in, or None to detect it; metadata with ``envconv:layout``
    set accordingly) of a texture file (see the module docstring)."""
    kind = f"{'cube map, 6 faces' if info.cube else '2-D texture'} of {info.width}x{info.height}"
    metadata = {
        **info.metadata,
        "envconv:container": f"{info.format.upper()} {kind}, "
        f"{info.levels} levels, {'float16' if info.dtype.endswith('2') else 'float32'}",
    }
    if not info.cube:
        return None, metadata
    tagged = metadata.get("envconv:layout")
    layout = get_layout(tagged) if tagged in _CUBE_LAYOUTS else get_layout("cube-hstrip")
    metadata.update({"envconv:layout": layout.name, "envconv:size": str(info.width),
                     "envconv:guard": "0"})  # fmt: skip
    return layout.name, metadata


_CUBE_LAYOUTS = ("cube-hstrip", "cube-vstrip", "cube-hcross", "cube-vcross")


def texture_size(info: TextureInfo, level: int) -> tuple[int, int]:
    """(width, height) of the map image of MIP ``level``."""
    width, height = max(info.width >> level, 1), max(info.height >> level, 1)
    if not info.cube:
        return width, height
    return get_layout(texture_layout(info)[0]).file_size(width, 0)


def texture_channels(info: TextureInfo) -> tuple[str, ...]:
    """The channels read: RGB, or RGBA when the alpha is data of its own."""
    return ("R", "G", "B", "A") if info.components == 4 and not info.opaque else ("R", "G", "B")


def texture_pixels(path: str, info: TextureInfo, level: int) -> np.ndarray:
    """The map image (H, W, C) float32 of MIP ``level`` of a texture file: its one image,
    or its six faces placed in :func:`texture_layout`'s layout."""
    if not 0 <= level < info.levels:
        raise ImageIOError(f"cannot read {path}: it has no MIP level {level} "
                           f"(levels 0 to {info.levels - 1})")  # fmt: skip
    keep = len(texture_channels(info))
    faces = [_image(path, info, face, level)[:, :, :keep] for face in range(6 if info.cube else 1)]
    if not info.cube:
        return faces[0]
    layout = get_layout(texture_layout(info)[0])
    n = faces[0].shape[0]
    image = np.zeros((layout.rows * n, layout.columns * n, keep), np.float32)
    for cell in layout.cells:
        face = faces[cell.face]
        image[cell.row * n : (cell.row + 1) * n, cell.col * n : (cell.col + 1) * n] = (
            np.rot90(face, 2) if cell.turns == 2 else face
        )
    return image


def _image(path: str, info: TextureInfo, face: int, level: int) -> np.ndarray:
    """One stored image as float32 (rows top first), read at its offset."""
    height, width = max(info.height >> level, 1), max(info.width >> level, 1)
    count = height * width * info.components
    data = np.fromfile(path, dtype=info.dtype, count=count, offset=info.images[(face, level)])
    if data.size != count:
        raise ImageIOError(f"cannot read {path}: it is cut short (level {level}, face {face})")
    image = data.reshape(height, width, info.components).astype(np.float32)
    return np.ascontiguousarray(image[::-1] if info.flip else image)
