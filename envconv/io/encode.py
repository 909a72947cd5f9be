"""How a map is stored in an output file: pixel type, colour space, clipping, compression.

:func:`encode_output` (inside :func:`envconv.io.write`):

1. The pixel type is ``bit_depth``, else the source's type where the format stores it, else
   the format's default (see ``envconv.io.FORMATS``).
2. Colour is converted from the map's colour space (its ``oiio:ColorSpace``, the working
   space for maps read by envconv) to ``output_colorspace``, else the default of the output
   format and pixel type (:func:`envconv.color.ocio.default_colorspace`).
3. Values are quantized (:func:`envconv.color.quantize.quantize`): 8-bit output is dithered unless
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
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..color import ocio as color
from ..color import quantize
from ..envmap import EnvMap
from .formats import WRITE_FORMATS, check_compression, choose_pixel_type, extension

__all__ = ["OutputPlan", "plan_output", "Encoded", "LazyLevel", "encode_output"]

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
    fmt = WRITE_FORMATS.get(extension(path), ("",))[0]
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
    #: The warnings known only once the levels were written (lazy levels): call it then.
    finish: Callable[[], list[str]] = list


def encode_output(
    envmap: EnvMap,
    path: str | os.PathLike,
    output_colorspace: str | None = None,
    bit_depth: str | None = None,
    dither: bool = True,
    ocio_config: str | os.PathLike | None = None,
    compression: str | None = None,
    lazy: bool = False,
) -> Encoded:
    """Convert, clip and quantize every level of ``envmap`` for writing to ``path``.

    See the module docstring.
    Clipping is reported for level 0 (lower levels are its averages). With ``lazy`` (not for
    DDS and KTX2) the levels are :class:`LazyLevel`, encoded a band of rows at a time as they
    are written, and the clipping warnings come from ``Encoded.finish()`` after writing.
    """
    plan = plan_output(path, envmap.pixel_type, envmap.metadata, output_colorspace, bit_depth,
                       ocio_config, compression)  # fmt: skip
    config = color.config_for(ocio_config)
    where = os.fspath(path)
    warnings: list[str] = []
    levels = envmap.levels if envmap.levels is not None else [envmap.pixels]
    lazy = lazy and plan.format not in ("dds", "ktx2")
    _check_memory(levels, plan, config, where, lazy)
    out, tally = [], []
    for k, level in enumerate(levels):
        if lazy:
            out.append(LazyLevel(quantize.as_image(level), plan, config, dither,
                                 tally if k == 0 else []))  # fmt: skip
            continue
        codes, report, n_neg = _encode_level(level, plan, config, dither)
        warnings.extend(_clip_warnings(where, [(report, n_neg)], level.shape))
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
    finish = (lambda: _clip_warnings(where, tally, levels[0].shape)) if lazy else list
    return Encoded(out, plan, metadata, warnings, finish)


def _clip_warnings(where: str, tally: list, shape) -> list[str]:
    """Warning lines for level 0 from the (clip report, RGBE negatives) of its blocks."""
    if not tally:
        return []
    warnings = []
    n_neg = sum(n for _, n in tally)
    if n_neg:
        warnings.append(
            f"{where}: Radiance HDR cannot store negative values; "
            f"{_percent(n_neg, shape[0] * shape[1])} of pixels had "
            "negative values set to 0 (write EXR or float TIFF to keep them)"
        )
    report = quantize.merge_reports([r for r, _ in tally])
    if report.message():
        warnings.append(f"{where}: {report.message()}")
    return warnings


#: Bytes of float32 pixels encoded at a time: colour conversion and quantisation make their
#: temporaries for one block of rows, never for a whole level (see docs/memory.md).
ENCODE_BLOCK_BYTES = 1 << 22


def _check_memory(levels: list[np.ndarray], plan: OutputPlan, config, where: str,
                  lazy: bool = False) -> None:  # fmt: skip
    """Refuse, before encoding, when the encoded copy of the levels cannot fit in memory."""
    from ..engine import memory

    held = sum(level.nbytes for level in levels)
    copy = _converts(plan, config) or plan.format == "hdr"
    share = {"float": 4 if copy else 0, "half": 2, "uint16": 2, "uint8": 1}.get(plan.pixel_type, 4)
    share = 0 if lazy else share
    memory.check(held + held * share // 4 + ENCODE_BLOCK_BYTES, f"writing {where}", held,
                 "write fewer levels or a smaller --size, or free memory")  # fmt: skip


def _converts(plan: OutputPlan, config) -> bool:
    """Whether writing converts colour (the source and output spaces differ)."""
    return color.resolve_colorspace(config, plan.source_colorspace) != color.resolve_colorspace(
        config, plan.colorspace)  # fmt: skip


def _encode_rows(block: np.ndarray, plan: OutputPlan, config, dither: bool, start: int = 0):
    """(codes, clip report, values of pixels zeroed for RGBE) of rows cut from a level whose
    first element here is element ``start`` of the level (the dither noise follows it)."""
    block = color.convert_keeping_nonfinite(block, plan.source_colorspace, plan.colorspace, config)
    n_neg = 0
    if plan.format == "hdr":
        block, n_neg = _clamp_for_rgbe(block)
    codes, report = quantize.quantize(block, plan.pixel_type, dither=dither, start=start)
    return codes, report, n_neg


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
        done, report, n = _encode_rows(
            level[y0 : y0 + rows], plan, config, dither, y0 * width * nch
        )
        if codes is None:
            codes = np.empty((height, width, nch), done.dtype)
        codes[y0 : y0 + rows] = done
        reports.append(report)
        n_neg += n
    return codes, quantize.merge_reports(reports), n_neg


class LazyLevel:
    """A level encoded only as its rows are written (:meth:`rows`), so no encoded copy of the
    whole level exists: what :func:`encode_output` gives with ``lazy=True``.

    ``shape`` and ``itemsize`` are those of the stored image; :meth:`take` picks channels (as
    ``codes[:, :, channels]`` would). Each band's clip report is added to ``tally``, from which
    :attr:`Encoded.finish` makes the warnings once the level is written."""

    def __init__(self, pixels, plan: OutputPlan, config, dither: bool, tally: list,
                 channels=None):  # fmt: skip
        self.pixels, self.plan, self.config, self.dither = pixels, plan, config, dither
        self.tally = tally
        self.channels = list(range(pixels.shape[2])) if channels is None else list(channels)
        stored = {"uint8": np.uint8, "uint16": np.uint16, "half": np.float16}
        self.itemsize = np.dtype(stored.get(plan.pixel_type, np.float32)).itemsize
        #: Rows to encode at a time: ENCODE_BLOCK_BYTES of float32 pixels.
        self.band_rows = max(1, ENCODE_BLOCK_BYTES // max(1, pixels.shape[1] * pixels.shape[2] * 4))

    @property
    def shape(self) -> tuple[int, int, int]:
        return (*self.pixels.shape[:2], len(self.channels))

    def take(self, channels) -> LazyLevel:
        return LazyLevel(self.pixels, self.plan, self.config, self.dither, self.tally,
                         [self.channels[c] for c in channels])  # fmt: skip

    def rows(self, y0: int, y1: int) -> np.ndarray:
        """Rows y0 … y1 − 1, encoded: a contiguous (y1 − y0, W, C) array of the stored type."""
        width, nch = self.pixels.shape[1:]
        codes, report, n_neg = _encode_rows(self.pixels[y0:y1], self.plan, self.config,
                                            self.dither, y0 * width * nch)  # fmt: skip
        self.tally.append((report, n_neg))
        if self.channels != list(range(nch)):
            codes = codes[:, :, self.channels]
        return np.ascontiguousarray(codes)


def _clamp_for_rgbe(pixels: np.ndarray) -> tuple[np.ndarray, int]:
    """Zero negative colour values (RGBE has no sign); return the pixels and how many had one."""
    sl = quantize.colour_slice(pixels.shape[2])
    neg = (pixels[..., sl] < 0).any(axis=2)
    n = int(neg.sum())
    return (np.where(neg[..., None], np.float32(0.0), pixels) if n else pixels), n


def _percent(part: int, whole: int) -> str:
    return f"{100 * part / whole:.3g}%" if whole else "0%"
