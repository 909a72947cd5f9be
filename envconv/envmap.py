"""EnvMap: an environment map in memory."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import LayoutError
from .layouts import Layout, get_layout

__all__ = ["EnvMap", "map_levels", "is_alpha", "alpha_channel"]


@dataclass
class EnvMap:
    """Pixels, layout and metadata of one environment map.

    Attributes
    ----------
    pixels : numpy.ndarray
        (H, W, C) float32, scene-linear, top row first. For multi-file layouts (cube-faces,
        paraboloid-split) the cells sit side by side as one mosaic, in face order.
    layout : Layout
        The layout; ``EnvMap(..., layout="latlong")`` accepts a name too.
    guard : int
        Guard-ring width G in pixels (0 for none).
    channels : tuple of str
        Channel names, e.g. ``("R", "G", "B")`` or ``("R", "G", "B", "A")``.
    metadata : dict
        File metadata (name → value) carried from the input to the output.
    pixel_type : str
        Storage type the pixels came from: ``"half"``, ``"float"``, ``"uint8"`` or ``"uint16"``.
    levels : list of numpy.ndarray, optional
        The mip chain, level 0 first: ``levels[k]`` is (H_k, W_k, C) float32 with
        ``H_k = max(H >> k, 1)``, ``W_k = max(W >> k, 1)`` (per file for multi-file layouts),
        same channels and the same uv ↔ direction mapping as ``pixels``; ``levels[0]`` is
        ``pixels``. None when the map has no mip chain (see :mod:`envconv.resample.mips`).
    valid : numpy.ndarray, optional
        (H, W) float32: 1 where the file held the pixel, 0 in a hole (a display-window pixel
        outside the data window; its channels are 0, alpha included). None when every pixel
        was held. Only maps read from files have one; resampling turns holes into alpha
        (see :mod:`envconv.resample.holes`).
    parts : tuple of (str, tuple of str)
        For a map read from several parts of a multi-part OpenEXR file: each part's name and
        its own channel names, in the order their channels sit in ``channels``. Written back
        as parts of those names; empty for a single image.
    """

    pixels: np.ndarray
    layout: Layout
    guard: int = 0
    channels: tuple[str, ...] = ()
    metadata: dict[str, Any] = field(default_factory=dict)
    pixel_type: str = "float"
    levels: list[np.ndarray] | None = None
    valid: np.ndarray | None = None
    parts: tuple[tuple[str, tuple[str, ...]], ...] = ()

    def __post_init__(self) -> None:
        self.layout = get_layout(self.layout)
        pixels = np.asarray(self.pixels)
        if pixels.ndim == 2:
            pixels = pixels[:, :, None]
        if pixels.ndim != 3:
            raise LayoutError(f"pixels must be (H, W, C), got shape {pixels.shape}")
        self.pixels = np.ascontiguousarray(pixels, dtype=np.float32)
        if not self.channels:
            self.channels = default_channel_names(self.pixels.shape[2])
        if len(self.channels) != self.pixels.shape[2]:
            raise LayoutError(
                f"{len(self.channels)} channel names for {self.pixels.shape[2]} channels"
            )
        self.channels = tuple(self.channels)
        _ = self.size  # validates that the pixels fit the layout
        if self.levels is not None:
            self._check_levels()
        if self.valid is not None:
            self.valid = np.ascontiguousarray(self.valid, dtype=np.float32)
            if self.valid.shape != self.pixels.shape[:2]:
                raise LayoutError(
                    f"valid has shape {self.valid.shape}; expected {self.pixels.shape[:2]}"
                )
        self.parts = tuple((str(name), tuple(names)) for name, names in self.parts)
        if self.parts and sum(len(names) for _, names in self.parts) != len(self.channels):
            raise LayoutError(f"parts hold {sum(len(n) for _, n in self.parts)} channels, "
                              f"the map {len(self.channels)}")  # fmt: skip

    def _check_levels(self) -> None:
        levels = [np.ascontiguousarray(level, dtype=np.float32) for level in self.levels]
        if not levels or levels[0].shape != self.pixels.shape:
            raise LayoutError("levels[0] must have the shape of pixels")
        for k, level in enumerate(levels[1:], 1):
            if level.ndim != 3 or level.shape[2] != self.pixels.shape[2]:
                raise LayoutError(f"mip level {k} has shape {level.shape}; expected (H, W, C)")
        levels[0] = self.pixels
        self.levels = levels

    @property
    def size(self) -> int:
        """Characteristic size N (docs/geometry.md, "Sizes": height of a lat-long, face edge, diameter)."""
        height, width = self.pixels.shape[:2]
        return self.layout.size_from_image(width, height, self.guard)

    @property
    def height(self) -> int:
        return int(self.pixels.shape[0])

    @property
    def width(self) -> int:
        return int(self.pixels.shape[1])

    @property
    def alpha_index(self) -> int | None:
        """Index of the alpha channel (:func:`alpha_channel`), or None."""
        return alpha_channel(self.channels)

    def __repr__(self) -> str:
        return (
            f"EnvMap({self.layout.name}, N={self.size}, G={self.guard}, "
            f"{self.width}x{self.height}x{len(self.channels)} {','.join(self.channels)})"
        )


def is_alpha(name: str) -> bool:
    """Whether a channel called ``name`` is an alpha channel: ``A`` or ``alpha``, any case.

    The one home of that rule: reading (holes get an ``A`` unless there is one), resampling
    (``alpha=True`` fills it or adds ``A``), writing (stored unassociated) and previews ask it.
    """
    return name.upper() == "A" or name.lower() == "alpha"


def alpha_channel(channels) -> int | None:
    """Index of the first alpha channel (:func:`is_alpha`) among ``channels``, or None."""
    return next((index for index, name in enumerate(channels) if is_alpha(name)), None)


def default_channel_names(count: int) -> tuple[str, ...]:
    """Conventional channel names for ``count`` channels (Y, RGB, RGBA, then numbered)."""
    if count == 1:
        return ("Y",)
    base = ("R", "G", "B", "A")
    return tuple(base[i] if i < 4 else f"channel{i}" for i in range(count))


def map_levels(envmap: EnvMap, fn, **changes: Any) -> EnvMap:
    """``envmap`` with ``fn`` applied to its pixels and to every MIP level it carries.

    ``fn`` takes and returns an ``(H, W, C)`` array; ``changes`` are other fields to replace
    (e.g. ``metadata``).
    """
    pixels = fn(envmap.pixels)
    if envmap.levels is not None:
        changes["levels"] = [pixels, *(fn(level) for level in envmap.levels[1:])]
    return dataclasses.replace(envmap, pixels=pixels, **changes)
