"""All numba options in one place.

Kernels are compiled with ``cache=True`` so that only the first run pays for compilation.
HDR images carry inf and nan, so the fast-math flags exclude ``nnan`` and ``ninf``.

Developers: numba checks a cached kernel against its own source file only. After editing a
helper in another module (a layout's map, ``kernels/cells.py``...), delete the stale caches:
``find envconv -name '*.nbi' -delete -o -name '*.nbc' -delete``.
"""

import numba

__all__ = ["jit", "jit_inline", "jit_parallel", "FASTMATH"]

#: LLVM fast-math flags that are safe with inf/nan data.
FASTMATH = {"nsz", "arcp", "contract", "afn", "reassoc"}


def jit(fn):
    """Compile a scalar helper or serial kernel (inlined into its callers by LLVM)."""
    return numba.njit(cache=True, fastmath=set(FASTMATH), error_model="numpy")(fn)


def jit_inline(fn):
    """Compile a helper that takes arrays, inlined into its callers at numba IR level.

    A call to a separately compiled function that receives arrays costs an atomic reference
    count increment and decrement per array; in a per-sample loop that both threads share,
    that dominates the run time. Inlining removes the call and the reference counting.
    """
    return numba.njit(cache=True, fastmath=set(FASTMATH), error_model="numpy", inline="always")(fn)


def jit_parallel(fn):
    """Compile a kernel whose outer ``prange`` loop runs across all cores."""
    return numba.njit(cache=True, parallel=True, fastmath=set(FASTMATH), error_model="numpy")(fn)
