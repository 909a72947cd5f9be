"""Engine-ready texture files: DDS and KTX2 cube maps (or 2-D textures) with their mip chains.

envconv writes these containers itself (:mod:`envconv.io.dds`, :mod:`envconv.io.ktx2`): no
maintained Python library writes float DDS or KTX2, and OpenImageIO reads neither float DDS
nor KTX2. A map in a GL-table cube layout (cube-faces, cube-hstrip, cube-vstrip, cube-hcross,
cube-vcross) is written as a cube map: its six faces, in the face order and orientation both
formats define, which are the layouts' own (the cross's rotated −Z_c cell is turned back).
Any other single-file layout is written as a 2-D texture of the whole image. Pixels are RGBA:
one channel is repeated into RGB, and a missing alpha is written as 1 and flagged opaque.
"""

from __future__ import annotations

import logging

import numpy as np

from ..layouts import Layout
from ..layouts.base import FAMILY_CUBE_GL
from .formats import CONTAINER_FORMATS  # the table lives with the other formats'
from .write_plan import container_levels

__all__ = ["CONTAINER_FORMATS", "cube_faces", "texture_images", "encode_texture"]

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
