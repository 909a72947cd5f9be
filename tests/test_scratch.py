"""envconv.kernels.scratch: arrays made inside a kernel without numba's np.empty.

Checked against numpy's own idea of such an array (shape, strides, dtype), against numba's
runtime allocation counters (every array freed), and for the typing errors of bad arguments.
"""

from __future__ import annotations

import numba
import numpy as np
import pytest
from numba.core.runtime import _nrt_python, rtsys

from envconv.kernels.scratch import scratch


@numba.njit
def _fill_3d(a, b, c):
    out = scratch((a, b, c), np.float32)
    for i in range(a):
        for j in range(b):
            for k in range(c):
                out[i, j, k] = 100 * i + 10 * j + k
    return out


@numba.njit
def _int_1d(n):
    out = scratch(n, np.int64)
    for i in range(n):
        out[i] = -i
    return out


@numba.njit
def _many(n):
    total = 0.0
    for i in range(n):
        tmp = scratch((i % 7 + 1, 3), np.float64)
        tmp[0, 0] = i
        total += tmp[0, 0]
    return total


def test_scratch_arrays_match_numpys_layout_and_hold_what_is_written():
    got = _fill_3d(3, 4, 5)
    expected = np.fromfunction(lambda i, j, k: 100 * i + 10 * j + k, (3, 4, 5), dtype=np.float32)
    assert got.dtype == np.float32 and got.flags.c_contiguous
    assert got.shape == expected.shape and got.strides == expected.strides
    np.testing.assert_array_equal(got, expected)
    ints = _int_1d(6)
    assert ints.dtype == np.int64 and ints.strides == (8,)
    np.testing.assert_array_equal(ints, -np.arange(6))
    assert _int_1d(0).shape == (0,)


def test_scratch_arrays_are_freed():
    _many(3)  # compile first: compiling allocates too
    _nrt_python.memsys_enable_stats()
    try:
        before = rtsys.get_allocation_stats()
        assert _many(1000) == sum(range(1000))
        after = rtsys.get_allocation_stats()
    finally:
        _nrt_python.memsys_disable_stats()
    assert after.mi_alloc - before.mi_alloc == after.mi_free - before.mi_free == 1000


def test_scratch_rejects_a_shape_that_is_not_integers():
    @numba.njit
    def bad(x):
        return scratch((x, 2), np.float64)

    with pytest.raises(numba.core.errors.TypingError):
        bad(1.5)
