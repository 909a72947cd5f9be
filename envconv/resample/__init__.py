"""Resampling: a map from one layout to another.

* :mod:`~envconv.resample.convert`: ``envconv.convert``, the resample of a whole map;
* :mod:`~envconv.resample.options`: the rules of its options (default size, samples, guard,
  mips, filters);
* :mod:`~envconv.resample.holes`: maps with missing pixels or several parts;
* :mod:`~envconv.resample.mips`, :mod:`~envconv.resample.ibl`: MIP chains, GGX and irradiance;
* :mod:`~envconv.resample.harmonics`: spherical-harmonic projection (``envconv sh``);
* :mod:`~envconv.resample.kernels`: the thin wrappers over the native core (``envconv._core``).

``from envconv.resample import default_size`` (the module's names before the regroup) still
works: those names are looked up in :mod:`~envconv.resample.convert` on first use.
"""

from __future__ import annotations

from ..lazy import package_getattr

__all__: list[str] = []

#: The names of :mod:`~envconv.resample.convert` this package still answers for.
FORWARDED = (
    "default_size", "auto_samples", "source_rips", "rip_row_cap", "memory_needed",
    "FILTERS", "MAX_SAMPLES",
)  # fmt: skip


__getattr__ = package_getattr(__name__, FORWARDED, "convert")
