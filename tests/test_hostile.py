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


# --- engine: outputs onto inputs, duplicate outputs, -n/--no-clobber, malformed graph files ---
# Usage refusals exit 2 once helper "messages" lands UsageError -> 2; until then 1 is accepted.

import os  # noqa: E402

import pytest  # noqa: E402


def _map(path, value=1.0):
    write_plain(path, np.full((8, 16, 3), value, np.float32))
    return path


def _refused(run, *folders, message=None):
    assert run.returncode in (1, 2), (run.returncode, run.stderr)
    assert_failed_cleanly(run, run.returncode, *folders, message=message)


def test_convert_refuses_a_hard_link_to_its_input_and_a_preview_onto_it(tmp_path):
    source = _map(tmp_path / "sky.exr")
    os.link(source, tmp_path / "hard.exr")
    before = snapshot(source)
    _refused(envconv("convert", source, tmp_path / "hard.exr", "--to", "sphere", "--size", "4"),
             tmp_path, message="input")  # fmt: skip
    _refused(envconv("convert", source, tmp_path / "o.exr", "--to", "sphere", "--size", "4",
                     "--preview", source), tmp_path, message="input")  # fmt: skip
    assert_untouched(before)
    assert not (tmp_path / "o.exr").exists()


def test_batch_refuses_to_write_onto_its_inputs(tmp_path):
    folder = tmp_path / "maps"
    folder.mkdir()
    maps = [_map(folder / "a.exr", 1.0), _map(folder / "b.exr", 2.0)]
    before = snapshot(*maps)
    run = envconv("batch", folder, "--out", "{dir}/{stem}.exr", "resample", "--to", "sphere",
                  "--size", "4")  # fmt: skip
    _refused(run, tmp_path, message="input")
    # Another job's input counts too: b's output would be a.exr.
    run = envconv("batch", maps[1], maps[0], "--out", str(folder / "a.exr"), "--skip-existing")
    _refused(run, tmp_path, message="input")
    assert_untouched(before)


def test_a_graph_file_refuses_to_write_onto_its_input(tmp_path):
    source = _map(tmp_path / "sky.exr")
    graph = tmp_path / "g.toml"
    graph.write_text('inputs = ["sky.exr"]\n[[steps]]\nstep = "resample"\nto = "latlong"\n'
                     'size = 8\n[[steps]]\nstep = "write"\npath = "{stem}.exr"\n')  # fmt: skip
    before = snapshot(source)
    _refused(envconv("run", graph), tmp_path, message="input")
    assert_untouched(before)


def test_two_outputs_of_one_run_on_one_path_are_refused_before_any_work(tmp_path):
    source = _map(tmp_path / "sky.exr")
    out = tmp_path / "out"
    chain = envconv("read", source, "resample", "--to", "latlong", "--size", "8", "write",
                    out / "x.exr", "resample", "--to", "sphere", "--size", "8", "write",
                    out / "x.exr")  # fmt: skip
    _refused(chain, tmp_path, message="twice")
    # One batch input, two resamples, one --out path: main wrote twice and listed it twice.
    batch = envconv("batch", source, "--out", out / "{stem}.exr", "--report", tmp_path / "r.json",
                    "resample", "--to", "latlong", "--size", "8", "resample", "--to", "sphere",
                    "--size", "8")  # fmt: skip
    _refused(batch, tmp_path, message="twice")
    other = _map(tmp_path / "other.exr")
    across = envconv("batch", source, other, "--out", out / "same.exr", "resample", "--to",
                     "sphere", "--size", "4")  # fmt: skip
    _refused(across, tmp_path, message="would both write")
    assert not out.exists() and not (tmp_path / "r.json").exists()


@pytest.mark.parametrize("command", ["convert", "write", "run", "batch"])
def test_no_clobber_refuses_an_existing_output(tmp_path, command):
    source = _map(tmp_path / "sky.exr")
    old = _map(tmp_path / "old.exr", 5.0)
    graph = tmp_path / "g.toml"
    graph.write_text('inputs = ["sky.exr"]\n[[steps]]\nstep = "resample"\nto = "latlong"\n'
                     'size = 8\n[[steps]]\nstep = "write"\npath = "old.exr"\n')  # fmt: skip
    args = {
        "convert": ["convert", "-n", source, old, "--to", "latlong", "--size", "8"],
        "write": ["read", source, "resample", "--to", "latlong", "--size", "8", "write",
                  tmp_path / "new.exr", "write", "-n", old],
        "run": ["run", "-n", graph],
        "batch": ["batch", "-n", source, "--out", old, "resample", "--to", "latlong"],
    }[command]  # fmt: skip
    before = snapshot(source, old)
    _refused(envconv(*args), tmp_path, message="no-clobber")
    assert_untouched(before)
    assert not (tmp_path / "new.exr").exists()
    # Without -n the old output is replaced (atomically, through a temp file).
    args.remove("-n")
    run = envconv(*args)
    assert run.returncode == 0, run.stderr
    assert snapshot(old) != {str(old): before[str(old)]}


@pytest.mark.parametrize(
    ("step", "key", "value", "expected"),
    [
        ("write", "bit_depth", "16", "one of half, float, uint8, uint16"),
        ("write", "compression", '["zip"]', "a compression name"),
        ("resample", "in_convention", "5", "a convention name"),
        ("resample", "mips", '"lots"', "true, false, a number of levels"),
        ("read", "fix_nonfinite", '"zero"', "one of none, black, box3, error"),
        ("write", "dither", '"yes"', "true or false"),
    ],
)
def test_malformed_graph_files_fail_before_reading_any_file(tmp_path, step, key, value, expected):
    """The input is garbage bytes: only a check before any read can give the key's error."""
    (tmp_path / "sky.exr").write_bytes(b"not an image at all")
    steps = {"read": '[[steps]]\nstep = "read"\n', "resample": "", "write": ""}
    extra = {step: f"{key} = {value}\n"}
    text = ('inputs = ["sky.exr"]\n' + steps["read"] + extra.get("read", "")
            + '[[steps]]\nstep = "resample"\nto = "latlong"\nsize = 8\n' + extra.get("resample", "")
            + '[[steps]]\nstep = "write"\npath = "out.exr"\n' + extra.get("write", ""))  # fmt: skip
    graph = tmp_path / "g.toml"
    graph.write_text(text)
    run = envconv("run", graph)
    _refused(run, tmp_path, message=f"key '{key}': expected {expected}")
    assert "step " in run.stderr and not (tmp_path / "out.exr").exists()


def test_a_variable_cycle_in_a_graph_file_is_an_error(tmp_path):
    _map(tmp_path / "sky.exr")
    graph = tmp_path / "g.toml"
    graph.write_text('inputs = ["sky.exr"]\n[vars]\na = "{b}"\nb = "{a}"\n[[steps]]\n'
                     'step = "resample"\nto = "latlong"\nsize = 8\n[[steps]]\nstep = "write"\n'
                     'path = "{a}.exr"\n')  # fmt: skip
    _refused(envconv("run", graph), tmp_path, message="cycle")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.toml", "sky.exr"]


def test_convert_and_the_chain_write_the_same_bytes(tmp_path):
    """convert is read → resample → write: the same file as the chain, byte for byte (but for
    the DateTime stamp), NaN handling and exposure included."""
    import re

    pixels = np.random.default_rng(15).uniform(0, 4, (16, 32, 3)).astype(np.float32)
    pixels[2, 3, 0] = np.nan
    source = tmp_path / "sky.exr"
    write_plain(source, pixels)
    opts = ["--exposure", "-1", "--fix-nonfinite", "box3"]
    a = envconv("convert", source, tmp_path / "a.exr", "--to", "cube-vcross", "--size", "8", *opts)
    b = envconv("read", source, *opts, "resample", "--to", "cube-vcross", "--size", "8", "write",
                tmp_path / "b.exr")  # fmt: skip
    assert a.returncode == b.returncode == 0, (a.stderr, b.stderr)
    assert a.stderr_lines == b.stderr_lines and len(a.stderr_lines) == 1  # the NaN warning
    stamp = re.compile(rb"\d{4}:\d\d:\d\d \d\d:\d\d:\d\d")
    bytes_a, bytes_b = ((tmp_path / n).read_bytes() for n in ("a.exr", "b.exr"))
    assert stamp.sub(b"", bytes_a) == stamp.sub(b"", bytes_b)


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
