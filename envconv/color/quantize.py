"""Quantisation and dither: float pixels to the values a file stores, and what was clipped.

Pixels are numpy arrays of shape ``(H, W, C)``. Colour channels are the first three when
``C >= 3``; a 1- or 2-channel image is grey (plus alpha), and its channel 0 is the colour.
Alpha and extra channels are never dithered. Nothing here knows about colour spaces (see
:mod:`envconv.color.ocio`) or files (see :mod:`envconv.io`). Every function is pure: nothing is
read, written or printed; what was clipped is returned as data (:class:`ClipReport`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import UsageError

__all__ = ["ClipReport", "HALF_MAX", "BIT_DEPTHS", "quantize", "merge_reports", "as_image",
           "colour_slice"]  # fmt: skip

HALF_MAX = 65504.0
"""Largest finite IEEE half-float value."""

#: Storage types :func:`quantize` knows, as OIIO names them.
BIT_DEPTHS = ("half", "float", "uint8", "uint16")

_INT_SCALE = {"uint8": 255.0, "uint16": 65535.0}

#: Values within this many codes of a code are on the grid: rounding is exact, no dither.
_ON_GRID = 2e-3


def as_image(pixels: Any) -> np.ndarray:
    """``pixels`` as a float32 ``(H, W, C)`` array (no copy when it already is one).

    Raises UsageError for any other shape.
    """
    arr = np.asarray(pixels, dtype=np.float32)
    if arr.ndim != 3 or arr.shape[2] < 1:
        raise UsageError(f"expected pixels of shape (H, W, C), got shape {arr.shape}")
    return arr


def colour_slice(nchannels: int) -> slice:
    """Slice of the colour channels: channel 0 for grey (C < 3), else the first three."""
    return slice(0, 3) if nchannels >= 3 else slice(0, 1)


@dataclass(frozen=True)
class ClipReport:
    """What writing at a given bit depth did to out-of-range values (all channels).

    For ``uint8``/``uint16`` a value counts as clipped when clipping changes its code: above
    ``1 + 0.5/max`` or below ``-0.5/max`` (values within half a code of [0, 1] round into range
    anyway), ±Inf included. For ``half`` it is outside [-65504, 65504], infinities excluded
    (:func:`count_nonfinite` reports those). ``float`` clips nothing.
    """

    bit_depth: str
    n_values: int
    n_pixels: int
    values_above: int = 0
    values_below: int = 0
    pixels_above: int = 0
    pixels_below: int = 0
    pixels_clipped: int = 0

    @property
    def fraction_values_above(self) -> float:
        return self.values_above / self.n_values if self.n_values else 0.0

    @property
    def fraction_values_below(self) -> float:
        return self.values_below / self.n_values if self.n_values else 0.0

    @property
    def fraction_pixels_clipped(self) -> float:
        return self.pixels_clipped / self.n_pixels if self.n_pixels else 0.0

    @property
    def clipped(self) -> bool:
        return self.pixels_clipped > 0

    def message(self) -> str | None:
        """One warning line for the CLI, or None when nothing was clipped."""
        if not self.clipped:
            return None
        frac = f"{100 * self.fraction_pixels_clipped:.3g}% of pixels"
        if self.bit_depth == "half":
            return (
                f"{frac} exceed the half-float limit {HALF_MAX:g} and were clamped to it; "
                "write float or use --exposure"
            )
        return (
            f"{self.bit_depth} output clips {frac} ({self.pixels_above} above 1, "
            f"{self.pixels_below} below 0); use --exposure STOPS or a float bit depth"
        )


def _clip_report(bit_depth: str, above: np.ndarray, below: np.ndarray) -> ClipReport:
    pa, pb = above.any(axis=2), below.any(axis=2)
    return ClipReport(
        bit_depth,
        int(above.size),
        int(pa.size),
        int(above.sum()),
        int(below.sum()),
        int(pa.sum()),
        int(pb.sum()),
        int((pa | pb).sum()),
    )


def _tpdf_noise(start: int, count: int) -> np.ndarray:
    """Deterministic triangular noise in (-1, 1) for flat element indices start..start+count-1.

    splitmix64 of the index; two 24-bit uniforms per element, subtracted.
    """
    z = np.arange(start, start + count, dtype=np.uint64)
    z = z * np.uint64(0x9E3779B97F4A7C15) + np.uint64(0x632BE59BD9B4E019)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z ^= z >> np.uint64(31)
    u1 = (z >> np.uint64(40)).astype(np.float32)
    u2 = (z & np.uint64(0xFFFFFF)).astype(np.float32)
    return (u1 - u2) * np.float32(2.0**-24)


def _dither_colour(codes: np.ndarray, scale: float, start: int = 0) -> None:
    """Add TPDF dither in place to colour codes strictly inside (0, scale), row block-wise;
    ``start`` is the flat index of the first element (of rows cut from a larger image).

    Codes already on the integer grid (within ``_ON_GRID``) are left alone: rounding them is
    exact, so an 8-bit image written again at 8 bits keeps its codes.
    """
    h, w, c = codes.shape
    sl = colour_slice(c)
    rows = max(1, (1 << 22) // max(1, w * c))
    for y0 in range(0, h, rows):
        block = codes[y0 : y0 + rows]
        noise = _tpdf_noise(start + y0 * w * c, block.size).reshape(block.shape)[..., sl]
        col = block[..., sl]
        with np.errstate(invalid="ignore"):  # NaN/Inf codes: never inside, nothing to warn
            inside = (col > 0) & (col < scale) & (np.abs(col - np.rint(col)) > _ON_GRID)
        block[..., sl] = np.where(inside, col + noise, col)


def merge_reports(reports: list[ClipReport]) -> ClipReport:
    """One :class:`ClipReport` of an image from the reports of its row blocks."""
    first = reports[0]
    fields = ("n_values", "n_pixels", "values_above", "values_below", "pixels_above",
              "pixels_below", "pixels_clipped")  # fmt: skip
    return ClipReport(first.bit_depth, *(sum(getattr(r, f) for r in reports) for f in fields))


def quantize(pixels: np.ndarray, bit_depth: str, dither: bool = True, start: int = 0):
    """Convert float pixels to the storage type of ``bit_depth`` and report what was clipped.

    Parameters
    ----------
    pixels : ndarray, shape (H, W, C)
        Float pixels, already in the output colour space (integer formats: 0..1 encoded).
    bit_depth : {'uint8', 'uint16', 'half', 'float'}
    dither : bool, default True
        For ``uint8`` only: add deterministic triangular (TPDF, ±1 LSB peak) dither to colour
        channels before rounding. The noise is a fixed hash of the element index, so the same
        input always gives the same output. Values that already sit on a code (within
        0.002 of one, e.g. 0, 1 or an 8-bit input written back at 8 bits) are not dithered;
        alpha and extra channels are only rounded.
    start : int, default 0
        Flat index of the first element in the whole image, when ``pixels`` are rows cut from
        it (the dither noise is a function of that index, so blocks quantize as the whole).

    Returns
    -------
    out : ndarray
        ``uint8``/``uint16``: integer codes ``round(clip(v, 0, 1) * max)`` (NaN becomes 0),
        ready to write without further scaling. ``half``: float16 with finite values clamped
        to ±65504 (inf and NaN kept). ``float``: float32, unchanged.
    report : ClipReport

    Examples
    --------
    >>> out, rep = quantize(np.array([[[0.5, 2.0, -1.0]]]), "uint8", dither=False)
    >>> out.ravel().tolist(), rep.values_above, rep.values_below
    ([128, 255, 0], 1, 1)
    """
    arr = as_image(pixels)
    if bit_depth == "float":
        return arr, ClipReport("float", int(arr.size), int(arr.shape[0] * arr.shape[1]))
    if bit_depth == "half":
        if arr.size and -HALF_MAX <= arr.min() and arr.max() <= HALF_MAX:  # (NaN: False)
            return arr.astype(np.float16), ClipReport("half", int(arr.size), int(arr.shape[0] * arr.shape[1]))  # fmt: skip
        fin = np.isfinite(arr)
        report = _clip_report("half", fin & (arr > HALF_MAX), fin & (arr < -HALF_MAX))
        out = arr
        if report.clipped:
            out = np.where(np.isfinite(arr), np.clip(arr, -HALF_MAX, HALF_MAX), arr)
        return out.astype(np.float16), report
    if bit_depth not in _INT_SCALE:
        raise UsageError(f"unknown bit depth {bit_depth!r}; expected uint8, uint16, half or float")
    scale = _INT_SCALE[bit_depth]
    codes = arr * np.float32(scale)
    report = _clip_report(bit_depth, codes >= scale + 0.5, codes < -0.5)
    if dither and bit_depth == "uint8":
        _dither_colour(codes, scale, start)
    codes = np.clip(np.rint(np.nan_to_num(codes, nan=0.0)), 0.0, scale)
    return codes.astype(np.dtype(bit_depth)), report
