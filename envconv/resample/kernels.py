"""Thin wrappers over the native core (``envconv._core``, C++17 under ``src/core/``).

Each function checks and converts its arrays (C-contiguous, the dtype the core takes),
allocates what it returns, and runs the core with the GIL released on :func:`get_threads`
threads. Geometry arrives as the four arrays of :func:`envconv.layouts.geometry.kernel_geometry`:
``geo = [family, N, G, N_x, columns, rows, then the chart's PARAM_COUNT parameters]`` (float64;
N_x is a cell's width without guard) and the int32 tables cell → face, cell → half turns,
face → cell. Image points are level-0 pixels, x right and y down; pixel
(i, j) spans [i, i+1) × [j, j+1).

Threads: every wrapper takes ``threads``, the count for that call. Left out, it is the count of
the enclosing :func:`threads_for` block in this thread (``envconv.convert(..., threads=2)``
runs all its kernels so), else the process setting: one per core by default (the CPUs this
process may run on), ``ENVCONV_THREADS`` or :func:`set_threads` (the CLI's ``--threads``; a
batch worker process's share). A per-call count never changes what other threads use, so two
threads of one process (a Dask worker's) may ask for different counts. Every task writes only
its own output rows, so the bytes do not depend on the thread count.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

import numpy as np

from .. import _core
from ..limits import MAX_THREADS, check_threads

__all__ = [
    "get_threads", "set_threads", "threads_for", "watch_progress", "resample_rows", "build_rips", "rip_level_count", "rip_offset",
    "reduce_blocks", "map_points_to_dirs", "map_dirs_to_points", "pixel_solid_angles",
    "dir_density", "face_to_dir", "dir_to_face", "density", "filtered_reads", "level_reads",
    "ibl_pyramid", "ibl_pyramid_binned", "ibl_pyramid_binned_any", "ibl_prefilter", "sh_project",
    "FILTER_NEAREST", "FILTER_BILINEAR", "FILTER_BICUBIC", "AREA_FILTER", "RIP_MIN_SPAN", "RIP_MAX_LEVELS",
    "TILE", "AUTO_MAX_SAMPLES", "AUTO_EDGE_SAMPLES", "FAMILY_LATLONG", "FAMILY_CUBE_GL",
    "FAMILY_CUBE_EXR", "FAMILY_SPHERE", "FAMILY_ANGULAR", "FAMILY_PARABOLOID", "FAMILY_TENNISBALL",
    "FAMILY_OCTAHEDRAL", "FAMILY_EQUAL_AREA", "FAMILY_EAC", "FAMILY_FISHEYE", "FAMILY_PERSPECTIVE",
    "DISK_FAMILIES", "PARAM_COUNT",
]  # fmt: skip

#: Filter codes (src/core/taps.h FilterCode): three point filters, and the area filter
#: (src/core/area.cpp) that integrates the box reconstruction over each pixel's footprint.
FILTER_NEAREST = _core.FILTER_NEAREST
FILTER_BILINEAR = _core.FILTER_BILINEAR
FILTER_BICUBIC = _core.FILTER_BICUBIC
AREA_FILTER = _core.FILTER_AREA
#: Geometry family codes, as the core dispatches on them (src/core/layouts.h); the layouts
#: take them from here (:mod:`envconv.layouts.base`), so Python never restates them.
FAMILY_LATLONG = _core.FAMILY_LATLONG
FAMILY_CUBE_GL = _core.FAMILY_CUBE_GL
FAMILY_CUBE_EXR = _core.FAMILY_CUBE_EXR
FAMILY_SPHERE = _core.FAMILY_SPHERE
FAMILY_ANGULAR = _core.FAMILY_ANGULAR
FAMILY_PARABOLOID = _core.FAMILY_PARABOLOID
FAMILY_TENNISBALL = _core.FAMILY_TENNISBALL
FAMILY_OCTAHEDRAL = _core.FAMILY_OCTAHEDRAL
FAMILY_EQUAL_AREA = _core.FAMILY_EQUAL_AREA
FAMILY_EAC = _core.FAMILY_EAC
FAMILY_FISHEYE = _core.FAMILY_FISHEYE
FAMILY_PERSPECTIVE = _core.FAMILY_PERSPECTIVE
#: Families whose valid region in a cell is the unit disk a² + b² ≤ 1 (``is_disk`` in the core).
DISK_FAMILIES = tuple(_core.DISK_FAMILIES)
#: Parameters of every chart (src/core/layouts.h kParamCount): two scales, the view frame (9,
#: row-major) and the reach of dir_to_face.
PARAM_COUNT = _core.PARAM_COUNT
#: Output tiles of TILE × TILE pixels interpolate the map (src/core/tiles.h).
TILE = _core.TILE
#: A lat-long pixel spanning X texels along x reads rip-map level k, the largest with
#: 2^k · RIP_MIN_SPAN ≤ X (src/core/footprint.h).
RIP_MIN_SPAN = float(_core.RIP_MIN_SPAN)
AUTO_MAX_SAMPLES = _core.AUTO_MAX_SAMPLES
AUTO_EDGE_SAMPLES = _core.AUTO_EDGE_SAMPLES
RIP_MAX_LEVELS = 8
RIP_MIN_WIDTH = 8


def _default_threads() -> int:
    value = os.environ.get("ENVCONV_THREADS", "").strip()
    if value:
        try:
            return min(max(1, int(value)), MAX_THREADS)
        except ValueError:
            pass
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


_threads = _default_threads()
#: The count of the enclosing :func:`threads_for` block: per thread (and per asyncio task).
_call_threads: ContextVar[int | None] = ContextVar("envconv_threads", default=None)


def get_threads(threads: int | None = None) -> int:
    """Threads a kernel call uses: ``threads`` when given, else the enclosing
    :func:`threads_for`'s count in this thread, else the process setting."""
    if threads is not None:
        return check_threads(threads)
    count = _call_threads.get()
    return _threads if count is None else count


def set_threads(count: int | None) -> int:
    """Set the process's count (None: the default; held to 1 … MAX_THREADS) for calls that
    give none; returns the previous one. For one call or one thread, pass ``threads`` or use :func:`threads_for`."""
    global _threads
    previous = _threads
    _threads = _default_threads() if count is None else min(max(1, int(count)), MAX_THREADS)
    return previous


@contextmanager
def threads_for(count: int | None) -> Iterator[None]:
    """Run the block's kernel calls, in this thread only, on ``count`` threads (None: as
    before the block)."""
    if count is None:
        yield
        return
    token = _call_threads.set(check_threads(count))
    try:
        yield
    finally:
        _call_threads.reset(token)


#: Called as ``watcher(done, total)`` with the bands of output rows finished, about 5 times a
#: second, while a resampling kernel runs (see :func:`watch_progress`).
_watcher: Callable[[int, int], None] | None = None


def watch_progress(watcher: Callable[[int, int], None] | None):
    """Report the progress of every resampling call to ``watcher(done, total)`` (None: stop);
    returns the previous watcher.

    With a watcher the kernel runs on a helper thread while the calling thread polls its
    counter of finished bands (the GIL is released inside the kernel), so a command line can
    draw a progress line; without one, nothing changes.
    """
    global _watcher
    previous, _watcher = _watcher, watcher
    return previous


def _run_watched(call, total: int, watch: bool = True) -> None:
    """Run ``call(progress)`` on a helper thread, reporting ``progress[0]`` to the watcher.

    The calling thread waits in short steps, so a signal (SIGINT, SIGTERM: an exception in
    the main thread, see :mod:`envconv.engine.interrupt`) is seen at once: the kernel is then
    cancelled between bands of rows (``_core.cancel``) and the exception goes on. ``watch``
    False: no progress to report (the call takes no counter).
    """
    watcher = _watcher if watch else None
    if watcher is None and threading.current_thread() is not threading.main_thread():
        call(None)  # signals reach the main thread only: nothing to wait for here
        return
    progress = np.zeros(1, np.int64)
    failure: list[BaseException] = []
    # The kernel must have returned before the calling thread lets an exception go: a process
    # that then ends would finalise the interpreter while the helper is still inside the core,
    # and the helper's return (taking the GIL back) would end its thread by a forced unwind
    # through the core's C++ frames: std::terminate, SIGABRT instead of one line (measured: a
    # Ctrl-C 30-50 ms into a small conversion, 1 to 3 times in 100, while Thread.start waited
    # for the helper to begin). So the helper starts the kernel only if the caller has not
    # given up yet, under a lock the caller takes when it gives up.
    gate = threading.Lock()
    state = {"abandoned": False, "running": False}
    finished = threading.Event()

    def work() -> None:
        with gate:
            if state["abandoned"]:
                finished.set()
                return
            state["running"] = True
        try:
            call(progress)
        except BaseException as exc:  # re-raised in the calling thread
            failure.append(exc)
        finally:
            finished.set()

    worker = threading.Thread(target=work, name="envconv-kernel", daemon=True)
    try:
        worker.start()  # its wait for the helper to begin can take the signal too
        while not finished.is_set():
            finished.wait(0.2 if watcher is not None else 0.05)
            if watcher is not None and not finished.is_set():
                watcher(int(progress[0]), total)
    except BaseException:
        with gate:
            state["abandoned"] = True
            running = state["running"]
        if running:
            _core.cancel(True)
            finished.wait()
            _core.cancel(False)
        raise
    if failure:
        raise failure[0]
    if watcher is not None:
        watcher(int(progress[0]), total)  # the end, however fast the kernel was


def _c(array, dtype) -> np.ndarray:
    return np.ascontiguousarray(array, dtype)


def _geo(geometry):
    geo, cell_face, cell_turns, face_cell = geometry
    return (
        _c(geo, np.float64),
        _c(cell_face, np.int32),
        _c(cell_turns, np.int32),
        _c(face_cell, np.int32),
    )


def resample_rows(
    src, rip, rip_levels, rip_rows, sgeometry, dgeometry, scale_x, scale_y, samples, filt, rot,
    fill, out, alpha=None, weights=None, zeroed=False, coverage_channel=False, threads=None,
    linear=False, valid_channel=-1,
):  # fmt: skip
    """Fill ``out`` (H, W, C float32) with ``src`` resampled; see :mod:`envconv.resample.convert`.

    ``alpha`` (H, W float32), when given, receives each pixel's valid-region coverage;
    ``weights`` (H, W float32) each pixel's sum of sub-sample weights (the solid-angle density
    of its readable sub-samples), from which the mip chain averages blocks with exactly the
    weights used here. ``rip`` holds ``rip_levels`` rip-map levels of a lat-long source
    (:func:`build_rips`), filled in the ``rip_rows`` rows next to each pole; they are read only
    with adaptive sampling (``samples`` ≤ 0) and the bilinear filter. ``rot`` (3, 3) maps
    output directions to source directions; ``scale_x``, ``scale_y`` are level-0 output pixels
    per pixel of ``out`` (1 for level 0 of a mip chain). ``zeroed``: the arrays already hold
    zeros (``np.zeros``), so pixels in a layout's empty cells are left as they are: their
    memory is never touched (half of a cross). ``coverage_channel``: ``out`` has one channel
    more than ``src`` and its last channel receives the coverage (an alpha channel resampled in
    place, with no second array; ``alpha`` must then be None). ``linear`` (area filter only):
    integrate the conservative piecewise-linear reconstruction (src/core/area_linear.h) instead
    of the box, for a conversion that magnifies; ``valid_channel``: the index of the source's V
    channel (holes, partial views), next to whose texels below 1 the box is kept, or -1.
    """
    args = (
        _c(src, np.float32), _c(rip, np.float32), int(rip_levels), int(rip_rows),
        *_geo(sgeometry), *_geo(dgeometry), float(scale_x), float(scale_y), int(samples),
        int(filt), _c(rot, np.float64), bool(fill), out, alpha, weights, get_threads(threads),
    )  # fmt: skip
    bands = (out.shape[0] + TILE - 1) // TILE
    _run_watched(lambda progress: _core.resample(*args, progress, bool(zeroed),
                                                 bool(coverage_channel), bool(linear),
                                                 int(valid_channel)), bands)  # fmt: skip


def rip_level_count(width: int) -> int:
    """Rip-map levels K a lat-long ``width`` texels wide carries: level k needs W / 2^k even
    (the pole continuation shifts by half of it) and at least RIP_MIN_WIDTH; at most 8."""
    levels = 0
    while (
        levels < RIP_MAX_LEVELS
        and width % (2 ** (levels + 2)) == 0
        and width >> (levels + 1) >= RIP_MIN_WIDTH
    ):
        levels += 1
    return levels


def rip_offset(width: int, level: int) -> int:
    """First column of ``level`` (≥ 1) in the packed rip-map of a source ``width`` wide."""
    return width - 2 * (width >> level)


def build_rips(src: np.ndarray, rows: int | None = None, out: np.ndarray | None = None,
               threads: int | None = None):  # fmt: skip
    """(packed levels, K) of a lat-long ``src`` (H, W, C) float32's horizontal rip-map.

    Level k (k ≥ 1) averages 2^k texels along x and none along y; levels 1 … K sit side by
    side in one (H, W − W / 2^K, C) float32 array, level k from column W − 2 W / 2^k. Only the
    ``rows`` rows next to each pole are filled (all when None); the kernel reads no other row.
    K = 0 (and a (1, 1, C) stand-in) when the width carries no level. ``out``, when given, is
    the array to fill.
    """
    src = _c(src, np.float32)
    height, width, nch = src.shape
    levels = rip_level_count(width)
    if levels == 0:
        return np.zeros((1, 1, nch), np.float32), 0
    if out is None:
        out = np.empty((height, width - (width >> levels), nch), np.float32)
    rows = height if rows is None else int(rows)
    _core.fill_rips(src, levels, rows, out, get_threads(threads))
    return out, levels


def reduce_blocks(src, wsrc, asrc, bx, by, out, wout, aout, threads=None) -> None:
    """Weighted means of bx × by blocks of ``src`` with weights ``wsrc``: ``out`` (h, w, C),
    the blocks' weight sums ``wout`` and mean coverages ``aout`` (``asrc`` and ``aout`` both
    None: no coverage)."""
    _core.reduce_blocks(
        _c(src, np.float32), _c(wsrc, np.float32), None if asrc is None else _c(asrc, np.float32),
        int(bx), int(by), out,
        wout, aout, get_threads(threads),
    )  # fmt: skip


def map_points_to_dirs(geometry, points, fill=False, threads=None):
    """(dirs (n, 3), flags (n,) int8) of level-0 image points (n, 2): flags 2 in the valid
    region, 1 in a guard ring (or anywhere with ``fill``), 0 no data (dirs 0 there)."""
    points = _c(points, np.float64).reshape(-1, 2)
    dirs = np.empty((points.shape[0], 3))
    flags = np.empty(points.shape[0], np.int8)
    _core.map_points_to_dirs(*_geo(geometry), points, bool(fill), dirs, flags,
                             get_threads(threads))  # fmt: skip
    return dirs, flags


def map_dirs_to_points(geometry, dirs, threads=None) -> np.ndarray:
    """Level-0 image points (n, 2) of unit directions (n, 3)."""
    dirs = _c(dirs, np.float64).reshape(-1, 3)
    points = np.empty((dirs.shape[0], 2))
    _core.map_dirs_to_points(*_geo(geometry), dirs, points, get_threads(threads))
    return points


def pixel_solid_angles(geometry, scale_x, scale_y, samples, shape, threads=None) -> np.ndarray:
    """Solid angle (sr) of the valid part of every pixel of an image of ``shape`` (H, W) whose
    pixels are ``scale_x`` × ``scale_y`` level-0 pixels, by S × S sub-samples."""
    out = np.empty(shape)
    _core.pixel_solid_angles(
        *_geo(geometry), float(scale_x), float(scale_y), int(samples), out, get_threads(threads)
    )
    return out


def dir_density(geometry, dirs) -> np.ndarray:
    """Solid-angle density (sr per unit (a, b) area) of the layout at unit directions (n, 3)."""
    dirs = _c(dirs, np.float64).reshape(-1, 3)
    out = np.empty(dirs.shape[0])
    _core.dir_density(*_geo(geometry), dirs, out)
    return out


def _flat_points(face, a, b):
    face, a, b = np.broadcast_arrays(np.asarray(face), np.asarray(a, float), np.asarray(b, float))
    return (
        face.shape,
        _c(face.ravel(), np.int32),
        _c(a.ravel(), np.float64),
        _c(b.ravel(), np.float64),
    )


def _params(params) -> np.ndarray:
    """The chart's parameters as the core takes them: PARAM_COUNT float64, zeros past those
    given."""
    out = np.zeros(PARAM_COUNT)
    values = np.asarray(params if params is not None else (), np.float64).ravel()
    out[: values.size] = values
    return out


def face_to_dir(family: int, face, a, b, params=None) -> np.ndarray:
    """Unit directions (..., 3) of points (a, b) of faces of geometry ``family`` with chart
    ``params``, continued past the valid region (see src/core/layouts.h)."""
    shape, face, a, b = _flat_points(face, a, b)
    out = np.empty((a.size, 3))
    _core.face_to_dir(int(family), _params(params), face, a, b, out)
    return out.reshape(*shape, 3)


def dir_to_face(family: int, dirs, params=None):
    """(face, a, b) arrays of unit directions (..., 3) in geometry ``family`` with chart
    ``params``."""
    dirs = np.asarray(dirs, np.float64)
    shape = dirs.shape[:-1]
    flat = _c(dirs.reshape(-1, 3), np.float64)
    face = np.empty(flat.shape[0], np.int32)
    a = np.empty(flat.shape[0])
    b = np.empty(flat.shape[0])
    _core.dir_to_face(int(family), _params(params), flat, face, a, b)
    return face.reshape(shape), a.reshape(shape), b.reshape(shape)


def density(family: int, face, a, b, params=None) -> np.ndarray:
    """Solid angle per unit (a, b) area (sr) at points (a, b) of faces of ``family`` with chart
    ``params``."""
    shape, face, a, b = _flat_points(face, a, b)
    out = np.empty(a.size)
    _core.density(int(family), _params(params), face, a, b, out)
    return out.reshape(shape)


def filtered_reads(src, geometry, cells, points, filt) -> np.ndarray:
    """Seam-aware filtered reads (n, C) of ``src`` at image points (n, 2) of ``cells`` (n,)."""
    src = _c(src, np.float32)
    points = _c(points, np.float64).reshape(-1, 2)
    out = np.empty((points.shape[0], src.shape[2]))
    cells = np.broadcast_to(np.asarray(cells, np.int64), points.shape[:1])
    _core.filtered_reads(src, *_geo(geometry), _c(cells, np.int64), points, int(filt), out)
    return out


def level_reads(rip, start, level_width, points) -> np.ndarray:
    """Bilinear reads (n, C) of one rip-map level (columns ``start`` … ``start + level_width``
    of ``rip``) at level points (n, 2), wrapping in x and continuing over the poles."""
    rip = _c(rip, np.float32)
    points = _c(points, np.float64).reshape(-1, 2)
    out = np.empty((points.shape[0], rip.shape[2]))
    _core.level_reads(rip, int(start), int(level_width), points, out)
    return out


def _pyramid_buffer(p: int, nch: int) -> np.ndarray:
    """An uninitialised float32 buffer for the pyramid of a p-cube with ``nch`` channels; its
    size is the core's (``Pyramid::floats_for`` in src/core/ibl.h, the one place it is computed)."""
    return np.empty(_core.ibl_pyramid_floats(int(p), int(nch)), np.float32)


def ibl_pyramid(faces: np.ndarray, threads: int | None = None) -> np.ndarray:
    """The GGX prefilter's pyramid of a cube's six faces (6, p, p, C) float32, p a power of
    two: every level's texel moments, packed as src/core/ibl.h describes."""
    faces = _c(faces, np.float32)
    p, nch = faces.shape[1], faces.shape[3]
    pyramid = _pyramid_buffer(p, nch)
    _core.ibl_pyramid(faces, pyramid, get_threads(threads))
    return pyramid


def ibl_pyramid_binned(
    latlong: np.ndarray, to_pyramid: np.ndarray, p: int, sub: int = 1, threads: int | None = None
) -> np.ndarray | None:
    """:func:`ibl_pyramid` of a p-cube made by binning every pixel of a lat-long (H, 2H, C)
    float32 (no guard ring), as ``sub`` × ``sub`` points, into the level-0 texel of its
    direction turned by ``to_pyramid`` (3 × 3): energy exact and a one-pixel sun kept at its
    own direction (src/core/ibl.h). None when some texel received no point (too coarse a
    source for p)."""
    latlong = _c(latlong, np.float32)
    nch = latlong.shape[2]
    pyramid = _pyramid_buffer(p, nch)
    done = _core.ibl_pyramid_binned(latlong, _c(to_pyramid, np.float64), int(p), int(sub),
                                    pyramid, get_threads(threads))  # fmt: skip
    return pyramid if done else None


def ibl_pyramid_binned_any(
    pixels: np.ndarray,
    geometry,
    to_pyramid: np.ndarray,
    p: int,
    sub: int,
    delta: float,
    threads: int | None = None,
) -> np.ndarray | None:
    """:func:`ibl_pyramid_binned` for a map of any layout (``geometry`` from
    :func:`envconv.layouts.geometry.kernel_geometry`): each owned pixel as ``sub`` × ``sub`` points
    (16 × 16 where only part of it is owned); ``delta`` bounds half a point's diagonal
    (radians). None when some texel received no point."""
    pixels = _c(pixels, np.float32)
    nch = pixels.shape[2]
    pyramid = _pyramid_buffer(p, nch)
    done = _core.ibl_pyramid_binned_any(pixels, *_geo(geometry), _c(to_pyramid, np.float64),
                                        int(p), int(sub), float(delta), pyramid,
                                        get_threads(threads))  # fmt: skip
    return pyramid if done else None


def ibl_prefilter(pyramid, p, nch, geometry, scale_x, scale_y, alpha, samples, rot, fill, tau,
                  out, threads=None) -> None:  # fmt: skip
    """Fill ``out`` (H, W, C) with the environment under the GGX lobe of roughness ``alpha``
    (α = r²; α = 1 with the clamped cosine: irradiance / π), read from ``pyramid``
    (:func:`ibl_pyramid` of a p-cube); ``tau`` bounds the expansion step (src/core/ibl.h)."""
    args = (
        pyramid, int(p), int(nch), *_geo(geometry), float(scale_x), float(scale_y), float(alpha),
        int(samples), _c(rot, np.float64), bool(fill), float(tau), out, get_threads(threads),
    )  # fmt: skip
    _run_watched(lambda _: _core.ibl_prefilter(*args), 0, watch=False)


def sh_project(pixels, geometry, samples: int, sign_x: float, threads=None) -> np.ndarray:
    """The 9 order-2 SH coefficients (9, C) of a map's pixels (R&H 2001, real orthonormal
    basis), by S × S sub-samples per pixel; ``sign_x`` −1 projects in the cube frame."""
    pixels = _c(pixels, np.float32)
    out = np.zeros((9, pixels.shape[2]))
    _core.sh_project(pixels, *_geo(geometry), int(samples), float(sign_x), out,
                     get_threads(threads))  # fmt: skip
    return out
