"""The native core through its bindings (envconv.resample.kernels, envconv._core).

Truth: the independent numpy reading of docs/geometry.md in tests/naive.py for every family's
maps and densities, and the core itself run on one thread for the thread-count invariance.
"""

from __future__ import annotations

import naive
import numpy as np
import pytest

import envconv
from envconv import _core
from envconv.layouts import get_layout
from envconv.layouts.geometry import kernel_geometry
from envconv.resample import kernels

# One layout of each geometry family, with the family's name in tests/naive.py.
FAMILIES = {
    "latlong": "latlong", "cube-hstrip": "cube", "cube-exr": "cube-exr", "sphere": "sphere",
    "angular": "angular", "paraboloid": "paraboloid", "tennisball": "tennisball",
    "octahedral": "octahedral", "equal-area": "equal-area",
}  # fmt: skip


def _valid_points(layout, count, rng):
    """Random (face, a, b) inside each face's valid region (the unit disk for disk layouts)."""
    face = rng.integers(0, layout.n_faces, count)
    a, b = rng.uniform(-1, 1, (2, count))
    if layout.disk:
        keep = a * a + b * b < 0.999
        face, a, b = face[keep], a[keep], b[keep]
    return face, a, b


@pytest.mark.parametrize("name", FAMILIES)
def test_face_to_dir_and_density_match_the_naive_reading(name):
    layout = get_layout(name)
    face, a, b = _valid_points(layout, 4000, np.random.default_rng(1))
    got = layout.face_to_dir(face, a, b)
    np.testing.assert_allclose(got, naive.face_to_dir(FAMILIES[name], face, a, b), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(got, axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(
        layout.density(face, a, b), naive.face_density(FAMILIES[name], face, a, b), rtol=1e-12
    )


@pytest.mark.parametrize("name", FAMILIES)
def test_dir_to_face_inverts_face_to_dir(name):
    """Direction → (face, a, b) → direction is the identity for random unit directions."""
    layout = get_layout(name)
    rng = np.random.default_rng(2)
    dirs = rng.normal(size=(4000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    face, a, b = layout.dir_to_face(dirs)
    assert face.min() >= 0 and face.max() < layout.n_faces
    limit = 1.0 + 1e-9
    if layout.disk:
        assert np.all(a * a + b * b <= limit)
    else:
        assert np.all(np.abs(a) <= limit) and np.all(np.abs(b) <= limit)
    np.testing.assert_allclose(layout.face_to_dir(face, a, b), dirs, atol=1e-9)


def test_maps_broadcast_and_keep_shapes():
    layout = get_layout("cube-vcross")
    dirs = layout.face_to_dir(np.arange(6)[:, None], np.linspace(-0.9, 0.9, 5)[None, :], 0.3)
    assert dirs.shape == (6, 5, 3)
    face, a, b = layout.dir_to_face(dirs)
    assert face.shape == a.shape == b.shape == (6, 5)
    np.testing.assert_array_equal(face, np.repeat(np.arange(6)[:, None], 5, axis=1))


@pytest.fixture(scope="module")
def noisy_sky():
    rng = np.random.default_rng(3)
    pixels = (rng.random((64, 128, 4)) * 10).astype(np.float32)
    pixels[5, 7] = 5e4  # a hot texel, so that regrouped sums would show
    return envconv.EnvMap(pixels, "latlong")


@pytest.mark.parametrize(
    "to, options",
    [
        ("cube-vcross", {"size": 40}),
        ("cube-vcross", {"size": 96, "samples": 1}),  # one tap a pixel, four floats stored at once
        ("octahedral", {"size": 96, "samples": 1, "alpha": True}),
        ("cube-vcross", {"size": 24, "samples": 3, "filter": "bicubic", "alpha": True}),
        ("sphere", {"size": 48, "guard": 2, "alpha": True, "rotate": (30, 10, 5)}),
        ("paraboloid", {"size": 32, "guard": "fill", "mips": True}),
        ("tennisball", {"size": 20, "filter": "nearest"}),
        ("latlong", {"size": 16}),  # a reduction: auto samples read the rip-map
    ],
)
def test_one_thread_and_many_threads_give_identical_bytes(noisy_sky, to, options):
    previous = kernels.set_threads(1)
    try:
        one = envconv.convert(noisy_sky, to, **options)
        kernels.set_threads(4)
        many = envconv.convert(noisy_sky, to, **options)
    finally:
        kernels.set_threads(previous)
    assert one.pixels.tobytes() == many.pixels.tobytes()
    for a, b in zip(one.levels or [], many.levels or [], strict=True):
        assert a.tobytes() == b.tobytes()


@pytest.mark.parametrize(
    "to, options",
    [
        ("cube-vcross", {"size": 96, "samples": 1}),
        ("cube-vcross", {"size": 40, "samples": 4, "alpha": True}),
        ("octahedral", {"size": 64, "samples": 3, "rotate": (30, 10, 5)}),
        ("latlong", {"size": 16}),  # auto samples on the rip-map
    ],
)
def test_avx_and_sse2_row_mappings_give_identical_bytes(noisy_sky, to, options):
    """The resampler maps rows four samples at a time with AVX where the CPU has it, else two
    at a time with SSE2; both must write the same bytes, so that machines with and without AVX
    convert a map identically. (On a CPU without AVX both runs take SSE2.)"""
    previous = _core.set_wide_rows(False)
    try:
        narrow = envconv.convert(noisy_sky, to, **options)
        _core.set_wide_rows(True)
        wide = envconv.convert(noisy_sky, to, **options)
    finally:
        _core.set_wide_rows(previous)
    assert narrow.pixels.tobytes() == wide.pixels.tobytes()


def test_threads_come_from_the_environment(monkeypatch):
    monkeypatch.setenv("ENVCONV_THREADS", "3")
    previous = kernels.set_threads(None)
    try:
        assert kernels.get_threads() == 3
    finally:
        kernels.set_threads(previous)
    assert kernels.set_threads(0) == previous and kernels.get_threads() == 1
    kernels.set_threads(previous)


def test_thread_counts_are_per_call_and_per_thread(noisy_sky, monkeypatch):
    """Two threads convert at once with threads=1 and threads=3, a third with none: each
    kernel call of each thread uses its own count (the process setting for the third), and
    the bytes are those of a one-thread run. (set_threads, a process global, was the only
    dial: a Dask worker's two threads changed each other's count.)"""
    import threading

    seen: dict[str, set[int]] = {}
    both_inside = threading.Barrier(3, timeout=30)
    resolve = kernels.get_threads

    def recording(threads=None):
        count = resolve(threads)
        name = threading.current_thread().name
        if name not in seen:
            seen[name] = set()
            both_inside.wait()  # every thread is inside convert before any goes on
        seen[name].add(count)
        return count

    monkeypatch.setattr(kernels, "get_threads", recording)
    previous = kernels.set_threads(2)
    results = {}

    def run(name, threads):
        results[name] = envconv.convert(noisy_sky, "cube-vcross", size=24, threads=threads)

    try:
        workers = [threading.Thread(target=run, args=(name, n), name=name)
                   for name, n in (("one", 1), ("three", 3), ("default", None))]  # fmt: skip
        for worker in workers:
            worker.start()
        for worker in workers:
            worker.join(60)
    finally:
        kernels.set_threads(previous)
    assert seen == {"one": {1}, "three": {3}, "default": {2}}
    monkeypatch.setattr(kernels, "get_threads", resolve)
    reference = envconv.convert(noisy_sky, "cube-vcross", size=24, threads=1)
    assert all(r.pixels.tobytes() == reference.pixels.tobytes() for r in results.values())
    with kernels.threads_for(5):
        assert kernels.get_threads() == 5 and kernels.get_threads(2) == 2
    with pytest.raises(envconv.UsageError, match="threads"):
        envconv.convert(noisy_sky, "latlong", size=4, threads=0)


def test_a_progress_watcher_sees_every_band_and_the_pixels_do_not_change(noisy_sky):
    seen = []
    plain = envconv.convert(noisy_sky, "cube-vcross", size=64)
    previous = kernels.watch_progress(lambda done, total: seen.append((done, total)))
    try:
        watched = envconv.convert(noisy_sky, "cube-vcross", size=64)
    finally:
        kernels.watch_progress(previous)
    assert seen and seen[-1] == (16, 16)  # 256 rows in bands of 16
    assert all(done <= total for done, total in seen)
    np.testing.assert_array_equal(plain.pixels, watched.pixels)


def test_a_kernel_error_reaches_the_caller_through_the_watcher():
    previous = kernels.watch_progress(lambda done, total: None)
    try:
        with pytest.raises((ValueError, TypeError)):
            kernels.resample_rows(
                np.zeros((4, 8, 3), np.float32), np.zeros((1, 1, 3), np.float32), 0, 0,
                kernel_geometry("latlong", 8), kernel_geometry("latlong", 4), 1.0, 1.0, 1, 1,
                np.eye(3), False, np.zeros((4, 8, 3), np.float32),
            )  # fmt: skip
    finally:
        kernels.watch_progress(previous)


def test_arrays_that_do_not_match_the_geometry_are_refused():
    src = np.zeros((4, 8, 3), np.float32)
    out = np.zeros((8, 16, 3), np.float32)
    with pytest.raises(ValueError, match="channel"):
        kernels.resample_rows(
            src, np.zeros((1, 1, 3), np.float32), 0, 0, kernel_geometry("latlong", 4),
            kernel_geometry("latlong", 8), 1.0, 1.0, 1, 1, np.eye(3), False,
            np.zeros((8, 16, 4), np.float32),
        )  # fmt: skip
    with pytest.raises(ValueError, match="source"):
        kernels.resample_rows(
            src, np.zeros((1, 1, 3), np.float32), 0, 0, kernel_geometry("latlong", 5),
            kernel_geometry("latlong", 8), 1.0, 1.0, 1, 1, np.eye(3), False, out,
        )  # fmt: skip


def test_nan_and_inf_positions_read_through_the_slow_path_without_crashing():
    """A NaN rotation sends every sample to a NaN direction: the kernel must still finish and
    produce NaN or finite values, never read outside the source."""
    sky = envconv.EnvMap(np.ones((16, 32, 3), np.float32), "latlong")
    rot = np.full((3, 3), np.nan)
    out = np.zeros((32, 24, 3), np.float32)
    kernels.resample_rows(
        sky.pixels, np.zeros((1, 1, 3), np.float32), 0, 0, kernel_geometry("latlong", 16),
        kernel_geometry("cube-vcross", 8), 1.0, 1.0, 2, 1, rot, False, out,
    )  # fmt: skip
    assert out.shape == (32, 24, 3)
