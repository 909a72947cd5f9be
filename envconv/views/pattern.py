"""A labelled test pattern: an analytic environment that shows orientation at a glance.

The pattern is a function of direction (envconv's world frame: right-handed, +Y up, +Z the
lat-long centre, +X at u = 0.25), so it can be rendered into any layout and any tool's
convention:

- **Base colour** codes the direction: ``0.5 + 0.4·(x, y, z)`` in (R, G, B), so +X is reddish,
  +Y greenish, +Z bluish and each opposite hemisphere is the complementary tint.
- **Grid**: parallels and meridians every 15° as thin dark lines; the equator and the four
  meridians through ±X and ±Z as thicker white lines. Meridians stop at |latitude| 75°.
- **Cube edges**: where two direction components tie in magnitude (the edges of every cube
  face), thin yellow lines, so cube layouts show their face borders.
- **Labels** "+X" "-X" "+Y" "-Y" "+Z" "-Z" centred on each axis: white 5×7 bitmap glyphs on a
  dark plate, drawn in the tangent plane of the axis (gnomonic projection), upright and
  unmirrored for a camera at the centre looking along the axis. "Up" is +Y for the four
  horizon labels, −Z for "+Y" and +Z for "-Y", so every label is upright in the cube faces and
  crosses of docs/geometry.md, and the horizon labels are upright in the lat-long.

Values lie in [0, 1]. Screen right for a camera looking along f with up vector u is f × u.
"""

from __future__ import annotations

import numpy as np

from ..envmap import EnvMap
from ..errors import UsageError
from ..layouts import get_layout
from ..layouts.conventions import apply_remap, resolve_convention
from ..layouts.geometry import uv_to_dir
from ..resample.regrid import check_output_grid, output_on_grid

__all__ = ["FONT", "LABELS", "GLYPH_UNIT", "pattern", "label_mask", "render_pattern"]

#: 5×7 bitmap glyphs, top row first, as seen by the reader ("#" = ink).
FONT = {
    "+": ("     ", "  #  ", "  #  ", "#####", "  #  ", "  #  ", "     "),
    "-": ("     ", "     ", "     ", "#####", "     ", "     ", "     "),
    "X": ("#   #", "#   #", " # # ", "  #  ", " # # ", "#   #", "#   #"),
    "Y": ("#   #", "#   #", " # # ", "  #  ", "  #  ", "  #  ", "  #  "),
    "Z": ("#####", "    #", "   # ", "  #  ", " #   ", "#    ", "#####"),
}
_GLYPHS = {ch: np.array([[c == "#" for c in row] for row in rows]) for ch, rows in FONT.items()}

#: Label text → (axis direction, up direction) in the world frame.
LABELS = {
    "+X": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "-X": ((-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "+Y": ((0.0, 1.0, 0.0), (0.0, 0.0, -1.0)),
    "-Y": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "+Z": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "-Z": ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
}

#: Size of one font pixel in the tangent plane (tan of the angle): ~3.4° at the label centre.
GLYPH_UNIT = 0.06
_MARGIN = 1  # plate margin around the text, in font pixels
_MINOR, _MAJOR, _EDGE = 0.3, 0.6, 0.3  # line half-widths in degrees


def _label_coords(d, text):
    """Font-pixel coordinates (col, row) of directions in a label's text box, and the mask."""
    axis, up = (np.asarray(v) for v in LABELS[text])
    right = np.cross(axis, up)
    depth = d @ axis
    with np.errstate(divide="ignore", invalid="ignore"):
        px = (d @ right) / depth / GLYPH_UNIT
        py = (d @ up) / depth / GLYPH_UNIT
    width = 6 * len(text) - 1
    col = px + width / 2.0
    row = 3.5 - py
    inside = (
        (depth > 0.5)
        & (col >= -_MARGIN)
        & (col < width + _MARGIN)
        & (row >= -_MARGIN)
        & (row < 7 + _MARGIN)
    )
    return col, row, inside


def label_mask(dirs, text: str):
    """Which directions are ink of label ``text`` (plate, ink) as two boolean arrays."""
    d = np.asarray(dirs, np.float64)
    col, row, plate = _label_coords(d, text)
    ink = np.zeros(d.shape[:-1], bool)
    ci = np.floor(np.where(plate, col, -1)).astype(int)
    ri = np.floor(np.where(plate, row, -1)).astype(int)
    for k, ch in enumerate(text):
        gc = ci - 6 * k
        hit = plate & (gc >= 0) & (gc < 5) & (ri >= 0) & (ri < 7)
        ink[hit] = _GLYPHS[ch][ri[hit], gc[hit]]
    return plate, ink


def _near_multiple(angle_deg, step, half_width):
    return np.abs(angle_deg - step * np.round(angle_deg / step)) < half_width


def pattern(dirs) -> np.ndarray:
    """Colour (..., 3) float64 of the labelled test pattern at unit directions (..., 3).

    Examples
    --------
    >>> c = pattern([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    >>> c.shape
    (2, 3)
    """
    d = np.asarray(dirs, np.float64)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    colour = 0.5 + 0.4 * d
    lat = np.degrees(np.arcsin(np.clip(y, -1.0, 1.0)))
    lon = np.degrees(np.arctan2(x, z))
    coslat = np.cos(np.radians(lat))
    minor = _near_multiple(lat, 15.0, _MINOR) | (
        (np.abs(lat) < 75.0) & _near_multiple(lon, 15.0, _MINOR / np.maximum(coslat, 1e-6))
    )
    major = (np.abs(lat) < _MAJOR) | (
        (np.abs(lat) < 75.0) & _near_multiple(lon, 90.0, _MAJOR / np.maximum(coslat, 1e-6))
    )
    colour[minor] *= 0.35
    colour[major] = 0.9
    mags = np.sort(np.abs(d), axis=-1)
    edge = (mags[..., 2] - mags[..., 1]) / np.sqrt(2.0) < np.radians(_EDGE)
    colour[edge] = (1.0, 0.8, 0.1)
    for text in LABELS:
        plate, ink = label_mask(d, text)
        colour[plate] = 0.03
        colour[ink] = 1.0
    return colour


def render_pattern(
    layout,
    size: int,
    samples: int = 2,
    convention=None,
    guard: int | str = 0,
    alpha: bool = False,
) -> EnvMap:
    """Render the test pattern into ``layout``, optionally in another tool's convention.

    Parameters
    ----------
    layout : str or Layout
        Output layout.
    size : int
        Characteristic size N.
    samples : int
        S × S sub-samples per pixel (plain mean over sub-samples that hold a direction).
    convention : str or array, optional
        Convention of the tool that will read the image (see :mod:`envconv.layouts.conventions`); the
        pattern is drawn so that this tool sees the labels at the right axes.
    guard : int or "fill"
        Guard ring in pixels, or ``"fill"``; guard pixels hold the continued mapping.
    alpha : bool
        Append an alpha channel: the fraction of sub-samples in the valid region.

    Returns
    -------
    EnvMap
        RGB (or RGBA) float32 in [0, 1]; pixels with no direction are 0.
    """
    layout = get_layout(layout)
    layout.validate_size(size)
    if not isinstance(samples, (int, np.integer)) or not 1 <= samples <= 16:
        raise UsageError(f"samples must be an integer from 1 to 16, got {samples!r}")
    fill = guard == "fill"
    guard_px = 0 if fill else int(guard)
    if guard_px < 0:
        raise UsageError(f"guard must be a non-negative integer or 'fill', got {guard!r}")
    conv = resolve_convention(convention, layout)
    check_output_grid(conv, None, guard)
    width, height = layout.image_size(size, guard_px)
    colour = np.zeros((height, width, 3))
    count = np.zeros((height, width))
    valid = np.zeros((height, width))
    for sy in range(samples):
        v = (np.arange(height) + (sy + 0.5) / samples) / height
        for sx in range(samples):
            u = (np.arange(width) + (sx + 0.5) / samples) / width
            uu, vv = np.meshgrid(u, v)
            dirs, flags = uv_to_dir(layout, uu, vv, size, guard_px, fill)
            has = flags > 0
            colour += np.where(has[..., None], pattern(dirs @ conv.matrix.T), 0.0)
            count += has
            valid += flags == 2
    pixels = colour / np.maximum(count, 1)[..., None]
    channels = ("R", "G", "B")
    if alpha:
        pixels = np.concatenate([pixels, (valid / samples**2)[..., None]], axis=2)
        channels += ("A",)
    pixels = apply_remap(layout, pixels, guard_px, conv.remap, inverse=True)
    pixels, metadata = output_on_grid(pixels, conv, {})  # a tool's own sample grid (mitsuba)
    return EnvMap(pixels.astype(np.float32), layout, guard=guard_px, channels=channels,
                  metadata=metadata)  # fmt: skip
