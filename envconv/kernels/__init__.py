"""Numba kernels: geometry dispatch and the fused resampler. Private; use envconv.resample."""

__all__: list[str] = []
