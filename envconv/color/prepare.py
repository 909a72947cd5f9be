"""A source map made ready for resampling: NaN and Inf, colour, exposure, negatives.

:func:`prepare_input` runs after :func:`envconv.io.read` and before resampling, in this order:

1. NaN and ±Inf are counted and reported, and ``fix_nonfinite`` (``none``, ``black``,
   ``box3``, ``error``: OIIO's ``fixNonFinite`` choices) replaces them, before the filter
   can spread them.
2. :func:`envconv.color.ocio.to_working` (a no-op for a map from :func:`envconv.io.read`).
3. ``exposure`` scales colour by 2**stops; then ``clamp_negative`` zeroes negatives.

Pixels are numpy arrays of shape ``(H, W, C)``; alpha and extra channels are never changed.
Nothing here prints: warnings are returned as lists of one-line strings.
"""

from __future__ import annotations

import os

import numpy as np

from ..envmap import EnvMap, map_levels
from ..errors import EnvconvError, UsageError
from . import ocio as color
from .quantize import as_image, colour_slice

__all__ = ["prepare_input", "FIX_MODES", "count_nonfinite", "fix_nonfinite", "clamp_negative"]

#: Modes of :func:`fix_nonfinite`, OIIO's ``fixNonFinite`` choices.
FIX_MODES = ("none", "black", "box3", "error")


def count_nonfinite(pixels: np.ndarray) -> tuple[int, int]:
    """Count NaN and ±Inf values (all channels). Returns ``(n_nan, n_inf)``.

    A finite sum proves there are none (a NaN or an Inf makes the sum NaN or Inf), in one pass
    without temporaries: 1 ms for a 2048 × 1024 RGB map against 7 ms for the counts, which are
    taken only when the sum is not finite (or overflows)."""
    arr = np.asarray(pixels)
    if arr.dtype.kind != "f":
        return 0, 0
    with np.errstate(over="ignore", invalid="ignore"):
        if np.isfinite(arr.sum()):
            return 0, 0
    return int(np.isnan(arr).sum()), int(np.isinf(arr).sum())


def _box3(arr: np.ndarray, bad: np.ndarray) -> np.ndarray:
    ys, xs, cs = np.nonzero(bad)
    h, w = arr.shape[:2]
    total = np.zeros(ys.shape, np.float64)
    count = np.zeros(ys.shape, np.int64)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            ny, nx = ys + dy, xs + dx
            inside = (ny >= 0) & (ny < h) & (nx >= 0) & (nx < w)
            v = arr[np.clip(ny, 0, h - 1), np.clip(nx, 0, w - 1), cs].astype(np.float64)
            ok = inside & np.isfinite(v)
            total += np.where(ok, v, 0.0)
            count += ok
    out = arr.copy()
    out[ys, xs, cs] = np.where(count > 0, total / np.maximum(count, 1), 0.0)
    return out


def fix_nonfinite(pixels: np.ndarray, mode: str = "box3") -> tuple[np.ndarray, int]:
    """Replace NaN and ±Inf values, with the choices of OIIO's ``fixNonFinite``.

    Parameters
    ----------
    pixels : ndarray, shape (H, W, C)
    mode : {'none', 'black', 'box3', 'error'}
        ``none`` leaves them; ``black`` sets them to 0; ``box3`` sets each to the mean of the
        finite values of the same channel in its 3x3 neighbourhood (inside the image), or 0
        if there are none; ``error`` raises. Unlike OIIO, which fixes pixels in raster order
        and reuses already-fixed neighbours, box3 here only averages originally finite values,
        so the result does not depend on scan order.

    Returns
    -------
    fixed : ndarray of float32
        A new array, or the input when nothing was replaced.
    count : int
        Number of values (not pixels) replaced.

    Raises
    ------
    EnvconvError
        In ``error`` mode when non-finite values are present.

    Examples
    --------
    >>> px = np.array([[[1.0], [np.nan], [3.0]]], np.float32)
    >>> fixed, n = fix_nonfinite(px, "box3")
    >>> fixed.ravel().tolist(), n
    ([1.0, 2.0, 3.0], 1)
    """
    if mode not in FIX_MODES:
        raise UsageError(f"unknown non-finite fix {mode!r}; expected one of {FIX_MODES}")
    arr = as_image(pixels)
    if mode == "none":
        return arr, 0
    bad = ~np.isfinite(arr)
    n_bad = int(bad.sum())
    if n_bad == 0:
        return arr, 0
    if mode == "error":
        n_nan, n_inf = count_nonfinite(arr)
        raise EnvconvError(
            f"input has {n_nan} NaN and {n_inf} Inf values; pass "
            "--fix-nonfinite black or box3 to replace them"
        )
    if mode == "black":
        return np.where(bad, np.float32(0.0), arr), n_bad
    return _box3(arr, bad), n_bad


def clamp_negative(pixels: np.ndarray) -> tuple[np.ndarray, int]:
    """Set negative colour values (including -Inf) to 0; NaN, alpha and extras untouched.

    Returns ``(array, n_clamped)``: a new float32 array (or the input when nothing was
    negative) and the number of values changed.

    Examples
    --------
    >>> out, n = clamp_negative(np.array([[[-0.1, 0.25, -3.0, -1.0]]], np.float32))
    >>> out.ravel().tolist(), n
    ([0.0, 0.25, 0.0, -1.0], 2)
    """
    arr = as_image(pixels)
    sl = colour_slice(arr.shape[2])
    neg = arr[..., sl] < 0
    n = int(neg.sum())
    if n == 0:
        return arr, 0
    out = arr.copy()
    out[..., sl] = np.where(neg, np.float32(0.0), arr[..., sl])
    return out, n


def _percent(part: int, whole: int) -> str:
    return f"{100 * part / whole:.3g}%" if whole else "0%"


def prepare_input(
    envmap: EnvMap,
    input_colorspace: str | None = None,
    ocio_config: str | os.PathLike | None = None,
    exposure: float = 0.0,
    fix_nonfinite: str = "none",
    clamp_negative: bool = False,
) -> tuple[EnvMap, list[str]]:
    """Prepare a source map for resampling (see the module docstring for the order).

    Parameters
    ----------
    envmap : EnvMap
        The source, e.g. from :func:`envconv.io.read` (already in the working space).
    input_colorspace : str, optional
        OCIO name, alias, role or friendly name (``srgb``, ``acescg``...) of the colour space
        ``envmap.pixels`` are in; default their ``oiio:ColorSpace`` (see :func:`to_working`).
        For a file's own colour space pass ``input_colorspace`` to :func:`envconv.io.read`
        instead: its result is already converted.
    ocio_config : str or path, optional
        Config file or ``ocio://`` URI; default ``$OCIO``, else ``ocio://default``.
    exposure : float
        Stops: colour is multiplied by ``2 ** exposure`` after the colour conversion.
    fix_nonfinite : {'none', 'black', 'box3', 'error'}
    clamp_negative : bool
        Set negative colour values to 0 (after exposure).

    Returns
    -------
    envmap : EnvMap
        float32 in the working space, ``oiio:ColorSpace`` set to it.
    warnings : list of str
        One line each, e.g. about NaN/Inf found in the input.
    """
    if fix_nonfinite not in FIX_MODES:
        raise UsageError(f"unknown --fix-nonfinite {fix_nonfinite!r}; choose one of "
                         f"{', '.join(FIX_MODES)}")  # fmt: skip
    warnings: list[str] = []
    n_nan, n_inf = count_nonfinite(envmap.pixels)
    if n_nan or n_inf:
        bad = int((~np.isfinite(envmap.pixels)).any(axis=2).sum())
        share = _percent(bad, envmap.height * envmap.width)
        found = f"input has {n_nan} NaN and {n_inf} Inf values in {share} of pixels"
        if fix_nonfinite == "none":
            warnings.append(f"{found}; the filter spreads them: pass --fix-nonfinite box3 or black")
        elif fix_nonfinite != "error":
            how = "0" if fix_nonfinite == "black" else "the mean of their finite 3x3 neighbours"
            warnings.append(f"{found}; replaced them with {how} (--fix-nonfinite {fix_nonfinite})")
        envmap = map_levels(envmap, lambda px: _replace_nonfinite(px, fix_nonfinite)[0])
    envmap = color.to_working(envmap, input_colorspace, ocio_config)
    if exposure:
        envmap = map_levels(envmap, lambda px: color.apply_exposure(px, exposure))
    if clamp_negative:
        envmap = map_levels(envmap, lambda px: _zero_negatives(px)[0])
    return envmap, warnings


# prepare_input's parameters ``fix_nonfinite`` and ``clamp_negative`` shadow these functions.
_replace_nonfinite, _zero_negatives = fix_nonfinite, clamp_negative
