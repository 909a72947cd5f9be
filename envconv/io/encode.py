"""How a map is stored in an output file: pixel type, colour space, clipping, compression.

:func:`encode_output` (inside :func:`envconv.io.write`):

1. The pixel type is ``bit_depth``, else the source's type where the format stores it, else
   the format's default (see ``envconv.io.FORMATS``).
2. Colour is converted from the map's colour space (its ``oiio:ColorSpace``, the working
   space for maps read by envconv) to ``output_colorspace``, else the default of the output
   format and pixel type (:func:`envconv.color.default_colorspace`).
3. Values are quantized (:func:`envconv.quantize.quantize`): 8-bit output is dithered unless
   ``dither=False``; values outside [0, 1] in an integer format and beyond ±65504 in half
   are clipped, with one warning line giving the fraction of pixels clipped. Radiance HDR
   cannot store negative numbers: they are set to 0, with a warning.
4. The output colour space is recorded in ``oiio:ColorSpace`` (as its interop id, e.g.
   ``srgb_rec709_scene``). Chromaticities that a conversion made stale are replaced (known
   spaces) or dropped.

Alpha and extra channels are never colour-converted or dithered: integer formats store alpha
linearly and unassociated. Nothing here prints: warnings are returned as one-line strings.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import color, quantize
from ..envmap import EnvMap
from .formats import WRITE_FORMATS, check_compression, choose_pixel_type

__all__ = ["OutputPlan", "plan_output", "Encoded", "encode_output"]

# xy of R, G, B and white, as OpenEXR's ``chromaticities`` attribute stores them.
_CHROMATICITIES = {
    "rec709": (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290),
    "ap1": (0.713, 0.293, 0.165, 0.830, 0.128, 0.044, 0.32168, 0.33767),
    "ap0": (0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.077, 0.32168, 0.33767),
}

# Formats whose OIIO writer drops ``oiio:ColorSpace`` (readers then apply the default rule).
_NO_COLORSPACE_TAG = ("tiff", "jpeg", "dds", "ktx2")

_PRIMARIES = re.compile(r"_(rec709|ap1|ap0)_scene$")

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
    fmt = WRITE_FORMATS.get(Path(os.fspath(path)).suffix.lower(), ("",))[0]
    ptype = choose_pixel_type(os.fspath(path), pixel_type, bit_depth)
    config = color.config_for(ocio_config)
    src = color.input_colorspace_of(metadata, pixel_type, None, ocio_config)
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
    config = color.config_for(ocio_config)
    where = os.fspath(path)
    warnings: list[str] = []
    levels = envmap.levels if envmap.levels is not None else [envmap.pixels]
    _check_memory(levels, plan, config, where)
    out = []
    for k, level in enumerate(levels):
        codes, report, n_neg = _encode_level(level, plan, config, dither)
        if k == 0 and n_neg:
            warnings.append(
                f"{where}: Radiance HDR cannot store negative values; "
                f"{_percent(n_neg, level.shape[0] * level.shape[1])} of pixels had "
                "negative values set to 0 (write EXR or float TIFF to keep them)"
            )
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

#: Bytes of float32 pixels encoded at a time: colour conversion and quantisation make their
#: temporaries for one block of rows, never for a whole level (see docs/memory.md).
ENCODE_BLOCK_BYTES = 1 << 22


def _check_memory(levels: list[np.ndarray], plan: OutputPlan, config, where: str) -> None:
    """Refuse, before encoding, when the encoded copy of the levels cannot fit in memory."""
    from .. import memory

    held = sum(level.nbytes for level in levels)
    copy = _converts(plan, config) or plan.format == "hdr"
    share = {"float": 4 if copy else 0, "half": 2, "uint16": 2, "uint8": 1}.get(plan.pixel_type, 4)
    memory.check(held + held * share // 4 + ENCODE_BLOCK_BYTES, f"writing {where}", held,
                 "write fewer levels or a smaller --size, or free memory")  # fmt: skip


def _converts(plan: OutputPlan, config) -> bool:
    """Whether writing converts colour (the source and output spaces differ)."""
    return color.resolve_colorspace(config, plan.source_colorspace) != color.resolve_colorspace(
        config, plan.colorspace)  # fmt: skip


def _encode_level(level: np.ndarray, plan: OutputPlan, config, dither: bool):
    """(codes, clip report, pixels with negatives zeroed for RGBE) of one level, encoded block
    of rows by block into one array of the stored type. A float level that needs no colour
    conversion is returned as it is (no copy)."""
    level = quantize.as_image(level)
    if plan.pixel_type == "float" and plan.format != "hdr" and not _converts(plan, config):
        codes, report = quantize.quantize(level, "float")
        return codes, report, 0
    height, width, nch = level.shape
    rows = max(1, ENCODE_BLOCK_BYTES // max(1, width * nch * 4))
    codes, reports, n_neg = None, [], 0
    for y0 in range(0, height, rows):
        block = color.convert_keeping_nonfinite(level[y0 : y0 + rows], plan.source_colorspace,
                                                plan.colorspace, config)  # fmt: skip
        if plan.format == "hdr":
            block, n = _clamp_for_rgbe(block)
            n_neg += n
        done, report = quantize.quantize(block, plan.pixel_type, dither=dither,
                                         start=y0 * width * nch)  # fmt: skip
        if codes is None:
            codes = np.empty((height, width, nch), done.dtype)
        codes[y0 : y0 + rows] = done
        reports.append(report)
    return codes, quantize.merge_reports(reports), n_neg


def _clamp_for_rgbe(pixels: np.ndarray) -> tuple[np.ndarray, int]:
    """Zero negative colour values (RGBE has no sign); return the pixels and how many had one."""
    sl = quantize.colour_slice(pixels.shape[2])
    neg = (pixels[..., sl] < 0).any(axis=2)
    n = int(neg.sum())
    return (np.where(neg[..., None], np.float32(0.0), pixels) if n else pixels), n


def _percent(part: int, whole: int) -> str:
    return f"{100 * part / whole:.3g}%" if whole else "0%"
