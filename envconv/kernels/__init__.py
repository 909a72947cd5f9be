"""Numba kernels: geometry dispatch and the fused resampler. Private; use envconv.resample."""

from .. import _jit  # noqa: F401 -- numba is imported the lean way (see _jit), first

__all__: list[str] = []
