"""Colour: the working space and every conversion (:mod:`~envconv.color.ocio`, the only module
that imports OpenColorIO), a source made ready for resampling (:mod:`~envconv.color.prepare`:
NaN/Inf, exposure, negatives), and bit depths, clipping and dither (:mod:`~envconv.color.quantize`).

``from envconv.color import to_working`` (the module's names before the regroup) still works:
those names are looked up in :mod:`~envconv.color.ocio` on first use.
"""

from __future__ import annotations

from ..lazy import package_getattr

__all__: list[str] = []

#: The names of :mod:`~envconv.color.ocio` this package still answers for.
FORWARDED = (
    "WORKING", "DEFAULT_COLORSPACE", "FILE_COLORSPACE", "colorspace_names",
    "resolve_colorspace", "to_working", "from_working", "convert_envmap", "display_view",
    "display_transform", "config_source", "is_linear", "ColorError",
)  # fmt: skip


__getattr__ = package_getattr(__name__, FORWARDED, "ocio")
