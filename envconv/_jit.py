"""All numba options in one place.

Kernels are compiled with ``cache=True`` so that only the first run pays for compilation.
HDR images carry inf and nan, so the fast-math flags exclude ``nnan`` and ``ninf``.
"""

import numba

__all__ = ["jit", "jit_parallel", "FASTMATH"]

#: LLVM fast-math flags that are safe with inf/nan data.
FASTMATH = {"nsz", "arcp", "contract", "afn", "reassoc"}


def jit(fn):
    """Compile a scalar helper or serial kernel (inlined into its callers by LLVM)."""
    return numba.njit(cache=True, fastmath=set(FASTMATH), error_model="numpy")(fn)


def jit_parallel(fn):
    """Compile a kernel whose outer ``prange`` loop runs across all cores."""
    return numba.njit(cache=True, parallel=True, fastmath=set(FASTMATH), error_model="numpy")(fn)
