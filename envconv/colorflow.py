"""Pixel values between a file and the resampler: colour spaces, range, bit depth, sample grid.

All resampling happens in scene-linear float32 in the *working space*, linear Rec.709
(OCIO's ``lin_rec709_scene``). Two functions frame it, for every path that reads or writes:

:func:`to_working` (inside :func:`envconv.io.read`)
    Colour is converted to the working space from the input colour space: ``input_colorspace``,
    else the file's ``oiio:ColorSpace``, else the format's default (float and half data, i.e.
    EXR, HDR and float TIFF: linear Rec.709; 8- and 16-bit PNG/JPEG/TIFF: sRGB-encoded
    Rec.709). NaN and Inf stay in their own channel.

:func:`prepare_input` (after :func:`envconv.io.read`, before resampling)
    1. NaN and ±Inf are counted and reported, and ``fix_nonfinite`` (``none``, ``black``,
       ``box3``, ``error``: OIIO's ``fixNonFinite`` choices) replaces them, before the filter
       can spread them.
    2. :func:`to_working` (a no-op for a map from :func:`envconv.io.read`).
    3. ``exposure`` scales colour by 2**stops; then ``clamp_negative`` zeroes negatives.

:func:`encode_output` (inside :func:`envconv.io.write`)
    1. The pixel type is ``bit_depth``, else the source's type where the format stores it, else
       the format's default (see ``envconv.io.FORMATS``).
    2. Colour is converted from the map's colour space (its ``oiio:ColorSpace``, the working
       space for maps read by envconv) to ``output_colorspace``, else the default of the
       output format and pixel type (same rule as for input).
    3. Values are quantized (:func:`envconv.depth.quantize`): 8-bit output is dithered unless
       ``dither=False``; values outside [0, 1] in an integer format and beyond ±65504 in half
       are clipped, with one warning line giving the fraction of pixels clipped. Radiance HDR
       cannot store negative numbers: they are set to 0, with a warning.
    4. The output colour space is recorded in ``oiio:ColorSpace`` (as its interop id, e.g.
       ``srgb_rec709_scene``). Chromaticities that a conversion made stale are replaced (known
       spaces) or dropped.

Alpha and extra channels are never colour-converted, exposed, clamped or dithered: integer
formats store alpha linearly and unassociated.

:func:`resample_edge_aligned` moves a lat-long stored with edge-aligned samples (OIIO's
``oiio:sampleborder`` = 1, OpenEXR ``ImfEnvmap``'s convention) onto envconv's pixel-centre grid.

Nothing here prints: warnings are returned as lists of one-line strings.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from . import color, depth
from .envmap import EnvMap
from .errors import UsageError

__all__ = [
    "WORKING_COLORSPACE",
    "COMPRESSIONS",
    "prepare_input",
    "to_working",
    "working_pixels",
    "encode_output",
    "plan_output",
    "OutputPlan",
    "Encoded",
    "input_colorspace_of",
    "check_compression",
    "resample_edge_aligned",
]

log = logging.getLogger(__name__)

#: The working space, as a friendly name resolved in the config (linear Rec.709).
WORKING_COLORSPACE = "linear"

#: ``--compression`` choices per OIIO format; ``name:level`` is accepted where marked ``:``.
COMPRESSIONS = {
    "openexr": ("none", "rle", "zips:", "zip:", "piz", "pxr24", "b44", "b44a", "dwaa:", "dwab:",
                "htj2k32", "htj2k256"),
    "tiff": ("none", "lzw", "zip:", "packbits"),
}  # fmt: skip

# xy of R, G, B and white, as OpenEXR's ``chromaticities`` attribute stores them.
_CHROMATICITIES = {
    "rec709": (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290),
    "ap1": (0.713, 0.293, 0.165, 0.830, 0.128, 0.044, 0.32168, 0.33767),
    "ap0": (0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.077, 0.32168, 0.33767),
}
# Formats whose OIIO writer drops ``oiio:ColorSpace`` (readers then apply the default rule).
_NO_COLORSPACE_TAG = ("tiff", "jpeg", "dds", "ktx2")
_PRIMARIES = re.compile(r"_(rec709|ap1|ap0)_scene$")


@lru_cache(maxsize=8)
def _load(path: str | None, env: str | None) -> Any:
    if path is None and not (env or "").strip():
        return color.builtin_config()
    return color.load_config(path)


def _config(ocio_config: str | os.PathLike | None) -> Any:
    """The config from ``ocio_config``, else ``$OCIO``, else ``ocio://default`` (cached)."""
    path = None if ocio_config is None else os.fspath(ocio_config)
    return _load(path, os.environ.get("OCIO"))


def _percent(part: int, whole: int) -> str:
    return f"{100 * part / whole:.3g}%" if whole else "0%"


def input_colorspace_of(
    metadata: dict, pixel_type: str, input_colorspace: str | None = None, ocio_config=None
) -> str:
    """Canonical name of the colour space a map's pixels are in (the input rule).

    ``input_colorspace`` when given, else the ``oiio:ColorSpace`` in ``metadata`` when the
    config knows it, else linear Rec.709 for float/half and sRGB for integer ``pixel_type``.
    """
    config = _config(ocio_config)
    if input_colorspace:
        return color.resolve_colorspace(config, input_colorspace)
    found = color.colorspace_from_metadata(metadata.get("oiio:ColorSpace"), config)
    return found or color.default_colorspace(config, "", pixel_type or "float")


def _map_levels(envmap: EnvMap, fn, **changes) -> EnvMap:
    """``envmap`` with ``fn`` applied to its pixels and every MIP level."""
    pixels = fn(envmap.pixels)
    if envmap.levels is not None:
        changes["levels"] = [pixels, *(fn(level) for level in envmap.levels[1:])]
    return dataclasses.replace(envmap, pixels=pixels, **changes)


def _convert(pixels: np.ndarray, src: str, dst: str, config: Any) -> np.ndarray:
    """Colour conversion that keeps NaN/Inf in their own channel (a matrix would spread them)."""
    if src == dst:  # nothing to convert: no NaN scan over the whole image
        return color.convert_colorspace(pixels, src, dst, config)
    sl = depth.colour_slice(pixels.shape[2])
    bad = ~np.isfinite(pixels[..., sl])
    if not bad.any():
        return color.convert_colorspace(pixels, src, dst, config)
    clean = pixels.copy()
    clean[..., sl] = np.where(bad, np.float32(0.0), pixels[..., sl])
    out = color.convert_colorspace(clean, src, dst, config)
    out[..., sl] = np.where(bad, pixels[..., sl], out[..., sl])
    return out


def working_pixels(
    pixels: np.ndarray,
    metadata: dict,
    pixel_type: str,
    input_colorspace: str | None = None,
    ocio_config: str | os.PathLike | None = None,
) -> np.ndarray:
    """``pixels`` of a file with this ``metadata`` and ``pixel_type``, converted to the
    working space as :func:`to_working` converts a map's (for images that are not maps)."""
    config = _config(ocio_config)
    src = input_colorspace_of(metadata, pixel_type, input_colorspace, ocio_config)
    return _convert(pixels, src, color.resolve_colorspace(config, WORKING_COLORSPACE), config)


def to_working(
    envmap: EnvMap,
    input_colorspace: str | None = None,
    ocio_config: str | os.PathLike | None = None,
) -> EnvMap:
    """Convert a map's colour to the working space (linear Rec.709); no-op if it is there.

    The map's colour space is ``input_colorspace``, else its ``oiio:ColorSpace``, else the
    format default for its ``pixel_type`` (see :func:`input_colorspace_of`).
    :func:`envconv.io.read` calls this, so maps it returns are already in the working space
    (give it ``input_colorspace`` to override the file's). ``oiio:ColorSpace`` is set to the
    working space; chromaticities are dropped when the colour changed (they described the
    input). NaN and Inf stay where they were.
    """
    config = _config(ocio_config)
    src = input_colorspace_of(envmap.metadata, envmap.pixel_type, input_colorspace, ocio_config)
    dst = color.resolve_colorspace(config, WORKING_COLORSPACE)
    metadata = dict(envmap.metadata)
    metadata.pop("colorInteropID", None)  # OIIO's EXR reader's copy of the colour space
    metadata["oiio:ColorSpace"] = color.metadata_name(config, dst)
    if src == dst:
        return dataclasses.replace(envmap, metadata=metadata)
    log.info("input colour space %s -> working space %s", src, dst)
    metadata.pop("chromaticities", None)
    return _map_levels(envmap, lambda px: _convert(px, src, dst, config), metadata=metadata)


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
    if fix_nonfinite not in depth.FIX_MODES:
        raise UsageError(f"unknown --fix-nonfinite {fix_nonfinite!r}; choose one of "
                         f"{', '.join(depth.FIX_MODES)}")  # fmt: skip
    warnings: list[str] = []
    n_nan, n_inf = depth.count_nonfinite(envmap.pixels)
    if n_nan or n_inf:
        bad = int((~np.isfinite(envmap.pixels)).any(axis=2).sum())
        share = _percent(bad, envmap.height * envmap.width)
        found = f"input has {n_nan} NaN and {n_inf} Inf values in {share} of pixels"
        if fix_nonfinite == "none":
            warnings.append(f"{found}; the filter spreads them: pass --fix-nonfinite box3 or black")
        elif fix_nonfinite != "error":
            how = "0" if fix_nonfinite == "black" else "the mean of their finite 3x3 neighbours"
            warnings.append(f"{found}; replaced them with {how} (--fix-nonfinite {fix_nonfinite})")
        envmap = _map_levels(envmap, lambda px: depth.fix_nonfinite(px, fix_nonfinite)[0])
    envmap = to_working(envmap, input_colorspace, ocio_config)
    if exposure:
        envmap = _map_levels(envmap, lambda px: depth.apply_exposure(px, exposure))
    if clamp_negative:
        envmap = _map_levels(envmap, lambda px: depth.clamp_negative(px)[0])
    return envmap, warnings


def check_compression(fmt: str, compression: str | None) -> str | None:
    """Validate ``compression`` for OIIO format ``fmt``; return it lower-cased (None: default).

    Raises UsageError naming the choices (or saying the format takes none).
    """
    if compression is None:
        return None
    value = str(compression).strip().lower()
    choices = COMPRESSIONS.get(fmt)
    if not choices:
        raise UsageError(f"{fmt} output takes no --compression (only EXR and TIFF do)")
    name, _, level = value.partition(":")
    for choice in choices:
        if name == choice.rstrip(":") and (not level or (choice.endswith(":") and level.isdigit())):
            return value
    shown = ", ".join(c.rstrip(":") for c in choices)
    raise UsageError(f"unknown {fmt} compression {compression!r}; choose one of {shown} "
                     "(zip, zips, dwaa and dwab take a level, e.g. dwaa:45)")  # fmt: skip


@dataclass(frozen=True)
class OutputPlan:
    """How a map will be stored in one output file (no pixels involved).

    Attributes: ``format`` (OIIO name), ``pixel_type``, ``source_colorspace`` and
    ``colorspace`` (canonical OCIO names), ``metadata_colorspace`` (the ``oiio:ColorSpace``
    written), ``compression`` (None: the format's default).
    """

    format: str
    pixel_type: str
    source_colorspace: str
    colorspace: str
    metadata_colorspace: str
    compression: str | None


def plan_output(
    path: str | os.PathLike,
    pixel_type: str,
    metadata: dict,
    output_colorspace: str | None = None,
    bit_depth: str | None = None,
    ocio_config: str | os.PathLike | None = None,
    compression: str | None = None,
) -> OutputPlan:
    """Decide pixel type, colour spaces and compression for writing to ``path``.

    ``pixel_type`` and ``metadata`` are the map's (its ``oiio:ColorSpace`` says what colour
    space its pixels are in; float data without one is taken as linear Rec.709).
    """
    from .formats import WRITE_FORMATS, choose_pixel_type

    fmt = WRITE_FORMATS.get(Path(os.fspath(path)).suffix.lower(), ("",))[0]
    ptype = choose_pixel_type(os.fspath(path), pixel_type, bit_depth)
    config = _config(ocio_config)
    src = input_colorspace_of(metadata, pixel_type, None, ocio_config)
    if output_colorspace:
        dst = color.resolve_colorspace(config, output_colorspace)
    else:
        dst = color.default_colorspace(config, fmt, ptype)
    return OutputPlan(fmt, ptype, src, dst, color.metadata_name(config, dst),
                      check_compression(fmt, compression))  # fmt: skip


@dataclass
class Encoded:
    """Pixels ready for the file: ``levels`` (level 0 first, dtype of ``plan.pixel_type``),
    the ``metadata`` to write, and one-line ``warnings``."""

    levels: list[np.ndarray]
    plan: OutputPlan
    metadata: dict[str, Any]
    warnings: list[str]


def encode_output(
    envmap: EnvMap,
    path: str | os.PathLike,
    output_colorspace: str | None = None,
    bit_depth: str | None = None,
    dither: bool = True,
    ocio_config: str | os.PathLike | None = None,
    compression: str | None = None,
) -> Encoded:
    """Convert, clip and quantize every level of ``envmap`` for writing to ``path``.

    See the module docstring.
    Clipping is reported for level 0 (lower levels are its averages).
    """
    plan = plan_output(path, envmap.pixel_type, envmap.metadata, output_colorspace, bit_depth,
                       ocio_config, compression)  # fmt: skip
    config = _config(ocio_config)
    where = os.fspath(path)
    warnings: list[str] = []
    levels = envmap.levels if envmap.levels is not None else [envmap.pixels]
    out = []
    for k, level in enumerate(levels):
        pixels = _convert(level, plan.source_colorspace, plan.colorspace, config)
        if plan.format == "hdr":
            pixels, n_neg = _clamp_for_rgbe(pixels)
            if n_neg and k == 0:
                warnings.append(
                    f"{where}: Radiance HDR cannot store negative values; "
                    f"{_percent(n_neg, pixels.shape[0] * pixels.shape[1])} of pixels had "
                    "negative values set to 0 (write EXR or float TIFF to keep them)"
                )
        codes, report = depth.quantize(pixels, plan.pixel_type, dither=dither)
        if k == 0 and report.message():
            warnings.append(f"{where}: {report.message()}")
        out.append(codes)
    if plan.format in _NO_COLORSPACE_TAG:
        assumed = color.default_colorspace(config, plan.format, plan.pixel_type)
        if assumed != plan.colorspace:
            warnings.append(
                f"{where}: {plan.format} files cannot record their colour space, and readers "
                f"assume {assumed}; read it back with --input-colorspace '{plan.colorspace}'"
            )
    metadata = dict(envmap.metadata)
    metadata.pop("colorInteropID", None)  # OIIO's EXR writer derives it from oiio:ColorSpace
    metadata["oiio:ColorSpace"] = plan.metadata_colorspace
    if plan.source_colorspace != plan.colorspace:
        metadata.pop("chromaticities", None)
    primaries = _PRIMARIES.search(plan.metadata_colorspace)
    if plan.format == "openexr" and primaries and "chromaticities" not in metadata:
        metadata["chromaticities"] = _CHROMATICITIES[primaries.group(1)]
    return Encoded(out, plan, metadata, warnings)


def _clamp_for_rgbe(pixels: np.ndarray) -> tuple[np.ndarray, int]:
    """Zero negative colour values (RGBE has no sign); return the pixels and how many had one."""
    sl = depth.colour_slice(pixels.shape[2])
    neg = (pixels[..., sl] < 0).any(axis=2)
    n = int(neg.sum())
    return (depth.clamp_negative(pixels)[0] if n else pixels), n


def _edge_weights(n: int) -> tuple[np.ndarray, np.ndarray]:
    """For centre k of n: left sample index and weight of the right one, on an edge grid."""
    x = (np.arange(n, dtype=np.float64) + 0.5) * (n - 1) / n
    i0 = np.minimum(np.floor(x).astype(np.intp), n - 2)
    return i0, (x - i0).astype(np.float32)


def resample_edge_aligned(pixels: np.ndarray) -> np.ndarray:
    """Resample an image with edge-aligned samples onto the pixel-centre grid, same size.

    In a file with ``oiio:sampleborder`` = 1 (what OIIO reports for every OpenEXR with an
    ``envmap`` attribute, after OpenEXR's ``ImfEnvmap``), sample (i, j) of a W × H image sits
    at u = i / (W − 1), v = j / (H − 1): the first and last columns both lie on the seam
    (lon = ±π) and the first and last rows on the poles. envconv's pixel (i, j) has its
    centre at ((i + 0.5) / W, (j + 0.5) / H), i.e. at file position (i + 0.5)(W − 1)/W.
    Each output value is the linear interpolation of the two nearest file samples, rows and
    columns separably (exact for constants and for functions linear in u and v). An axis of
    one sample is left as it is.

    Parameters
    ----------
    pixels : ndarray, shape (H, W, C)

    Returns
    -------
    ndarray of float32, shape (H, W, C)

    Examples
    --------
    >>> px = np.arange(3, dtype=np.float32).reshape(1, 3, 1) * np.ones((2, 1, 1), np.float32)
    >>> [round(float(x), 4) for x in resample_edge_aligned(px)[0, :, 0]]  # u = 1/6, 1/2, 5/6
    [0.3333, 1.0, 1.6667]
    """
    out = depth.as_image(pixels)
    height, width = out.shape[:2]
    if height > 1:
        j0, t = _edge_weights(height)
        t = t[:, None, None]
        out = out[j0] * (1 - t) + out[j0 + 1] * t
    if width > 1:
        i0, t = _edge_weights(width)
        t = t[None, :, None]
        out = out[:, i0] * (1 - t) + out[:, i0 + 1] * t
    return np.ascontiguousarray(out, np.float32)
