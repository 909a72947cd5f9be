"""The fault suite: hostile inputs, arguments and faults, each proven to fail cleanly.

Each case states its expectation through tests/hostile.py: exit 2 for usage and 1 for a
run-time failure, one line on stderr, no traceback, nothing on stdout, no temporary files left,
inputs and old outputs untouched. Sections are grouped by what is attacked.
"""

from __future__ import annotations

import numpy as np
from conftest import write_plain
from hostile import assert_failed_cleanly, assert_untouched, envconv, snapshot

# --- outputs onto inputs ---------------------------------------------------------------------


def test_convert_refuses_to_write_onto_its_input(tmp_path):
    source = tmp_path / "sky.exr"
    write_plain(source, np.ones((8, 16, 3), np.float32))
    before = snapshot(source)
    run = envconv("convert", source, source, "--to", "cube-vcross", "--size", "4")
    assert_failed_cleanly(run, run.returncode, tmp_path, message="input")
    assert run.returncode in (1, 2)
    assert_untouched(before)


# --- memory: the memory guard (envconv.memory, docs/memory.md) --------------------------------


def _small_latlong(tmp_path):
    source = tmp_path / "sky.exr"
    write_plain(source, np.full((16, 32, 3), 0.5, np.float32))
    return source


def _refused_quickly(run, tmp_path, elapsed: float) -> None:
    """Exit 1 (a run-time failure: the same command fits on a larger machine), one line that
    names the memory needed and available, in seconds, no output file and no litter."""
    assert_failed_cleanly(run, 1, tmp_path, message="of memory and")
    assert "is available" in run.stderr and "--size" in run.stderr
    assert elapsed < 15, elapsed
    assert not (tmp_path / "out.exr").exists()


def test_size_12000_is_refused_before_allocating(tmp_path):
    """issue 15: --size 12000 from a small map was OOM-killed (exit 137) on a 24 GB machine.
    ENVCONV_MEMORY_LIMIT stands for a machine of 2 GB, so the case holds on any machine."""
    import time

    source = _small_latlong(tmp_path)
    before = snapshot(source)
    start = time.monotonic()
    run = envconv("convert", source, tmp_path / "out.exr", "--to", "cube-vcross", "--size",
                  "12000", env={"ENVCONV_MEMORY_LIMIT": "2G"})  # fmt: skip
    _refused_quickly(run, tmp_path, time.monotonic() - start)
    assert "cube-vcross at size 12000" in run.stderr and "(ENVCONV_MEMORY_LIMIT)" in run.stderr
    assert_untouched(before)


def test_size_100000_is_refused_before_allocating(tmp_path):
    """issue 15: --size 100000 said "internal error: MemoryError". 2 TB fits no machine, so no
    limit is set: the real MemAvailable is read."""
    import time

    source = _small_latlong(tmp_path)
    start = time.monotonic()
    run = envconv("convert", source, tmp_path / "out.exr", "--to", "cube-vcross", "--size",
                  "100000", env={"ENVCONV_MEMORY_LIMIT": ""})  # fmt: skip
    _refused_quickly(run, tmp_path, time.monotonic() - start)


def test_chain_step_is_refused_before_allocating(tmp_path):
    """Chains go through the same guard (it sits in resampling, not in one command)."""
    source = _small_latlong(tmp_path)
    run = envconv("read", source, "resample", "--to", "latlong", "--size", "40000", "write",
                  tmp_path / "out.exr", env={"ENVCONV_MEMORY_LIMIT": "1G"})  # fmt: skip
    assert_failed_cleanly(run, 1, tmp_path, message="latlong at size 40000 needs about")


def test_huge_display_window_is_refused_before_reading(tmp_path):
    """A small file whose display window is 200000 × 100000 (its data window 4 × 4): reading
    would place it in a 320 GB array. Refused from the header, before any pixel is read."""
    import OpenImageIO as oiio

    path = tmp_path / "huge.exr"
    spec = oiio.ImageSpec(4, 4, 3, oiio.HALF)
    spec.full_width, spec.full_height = 200000, 100000
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec) and out.write_image(np.ones((4, 4, 3), np.float32))
    out.close()
    before = snapshot(path)
    run = envconv("convert", path, tmp_path / "out.exr", "--to", "cube-vcross", "--size", "8",
                  env={"ENVCONV_MEMORY_LIMIT": "4G"})  # fmt: skip
    assert_failed_cleanly(run, 1, tmp_path, message=f"reading {path} needs about")
    assert_untouched(before)


def test_under_the_limit_converts(tmp_path):
    """The guard refuses only what does not fit: the same map at a size that fits converts."""
    source = _small_latlong(tmp_path)
    run = envconv("convert", source, tmp_path / "out.exr", "--to", "cube-vcross", "--size",
                  "64", env={"ENVCONV_MEMORY_LIMIT": "2G"})  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "out.exr").is_file()


def test_ulimit_is_respected(tmp_path):
    """Under ``ulimit -v 4G`` a 5 GB conversion is refused with one line (it was "internal
    error: MemoryError", exit 3)."""
    import resource

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))

    source = _small_latlong(tmp_path)
    run = envconv("convert", source, tmp_path / "out.exr", "--to", "cube-vcross", "--size",
                  "6000", env={"ENVCONV_MEMORY_LIMIT": ""}, preexec_fn=limit)  # fmt: skip
    assert_failed_cleanly(run, 1, tmp_path, message="cube-vcross at size 6000 needs about")
