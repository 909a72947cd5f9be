"""The fault suite: hostile inputs, arguments and faults, each proven to fail cleanly.

Each case states its expectation through tests/hostile.py: exit 2 for usage and 1 for a
run-time failure, one line on stderr, no traceback, nothing on stdout, no temporary files left,
inputs and old outputs untouched. Sections are grouped by what is attacked.
"""

from __future__ import annotations

import json
import os
import re
import resource
import signal
import struct
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import run_cli, write_plain
from hostile import ENVCONV, Run, assert_failed_cleanly, assert_untouched, envconv, litter, snapshot

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


# --- memory: the memory guard (envconv.engine.memory, docs/memory.md) --------------------------------


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


# --- faults: temp files, write errors, signals, dead workers ---------------------------------
# Truth: the exit status and the one line the issue asks for; files compared by bytes with a
# snapshot taken before the run; outputs read back and compared with the analytic constant of
# their input; temp files found by name (hostile.litter).


def _noise(path, height=64, seed=0):
    """A lat-long of random values: compresses badly, so its outputs are large."""
    pixels = np.random.default_rng(seed).random((height, 2 * height, 3), dtype=np.float32)
    write_plain(path, pixels)
    return path


def _dead_pid() -> int:
    child = subprocess.Popen(["true"])
    child.wait()
    return child.pid


def _start(*args, **popen) -> subprocess.Popen:
    """``envconv ARGS`` in its own process group (a terminal's Ctrl-C reaches the group)."""
    return subprocess.Popen([ENVCONV, *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, **popen)  # fmt: skip


def _wait_for(predicate, timeout=60.0, step=0.002):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        found = predicate()
        if found:
            return found
        time.sleep(step)
    raise AssertionError("timed out waiting")


def _signal_after(process, signum, predicate, timeout=60.0):
    """Send ``signum`` to the process group once ``predicate()`` holds; return (seconds from
    the signal to the exit, stdout, stderr)."""
    try:
        _wait_for(lambda: predicate() or process.poll() is not None, timeout)
        assert process.poll() is None, process.communicate()
        sent = time.monotonic()
        os.killpg(process.pid, signum)
        out, err = process.communicate(timeout=30)
    except BaseException:  # a failed case leaves no process behind
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()
        raise
    return time.monotonic() - sent, out, err


def test_temp_files_are_never_inputs_and_stale_ones_are_cleaned(tmp_path):
    """A killed run's temps (old and new names) are no batch inputs and the next write into
    their folder removes them; a live run's temp (its lock held) is left alone."""
    import fcntl

    from envconv.io.temps import _host

    source = tmp_path / "sky.exr"
    write_plain(source, np.ones((8, 16, 3), np.float32))
    data = source.read_bytes()
    dead, host = _dead_pid(), _host()
    stale = [tmp_path / f".sky.envconv-{dead}.tmp.exr",
             tmp_path / f".old.envconv-{host}-{dead}-0badf00d.tmp.exr"]  # fmt: skip
    live = tmp_path / f".new.envconv-{host}-{os.getpid()}-00c0ffee.tmp.exr"
    for path in (*stale, live):
        path.write_bytes(data)  # a whole image: a batch that took it would convert it
    report = tmp_path / "report.json"
    with open(live, "rb") as owner:
        fcntl.flock(owner, fcntl.LOCK_EX)  # what a live run holds
        run = envconv("batch", tmp_path, "--out", tmp_path / "{stem}_cross.exr", "--report",
                      report, "resample", "--to", "cube-vcross", "--size", 4)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert [r["input"] for r in json.loads(report.read_text())["files"]] == [str(source)]
    assert sorted(os.listdir(tmp_path)) == sorted(
        [live.name, "report.json", "sky.exr", "sky_cross.exr"]
    )
    assert source.read_bytes() == data


def test_temp_names_and_other_hosts_temps(tmp_path):
    """Only envconv's temp names are recognised; another machine's temp in a shared folder
    is kept while it may still be written (a day), then removed."""
    from envconv.io.temps import FOREIGN_AGE, _host, clean_stale, is_temp_name

    assert is_temp_name(".sky.envconv-0a1b2c3d-42-deadbeef.tmp.exr")
    assert is_temp_name(".sky.envconv-42.tmp.exr")  # older envconv versions
    for name in ("sky.exr", ".sky.exr", "sky.envconv.tmp.exr", ".sky.envconv-x.tmp.exr"):
        assert not is_temp_name(name), name
    host = "e" * 8 if _host() == "f" * 8 else "f" * 8  # not this machine
    foreign = tmp_path / f".sky.envconv-{host}-{_dead_pid()}-00000000.tmp.exr"
    foreign.write_bytes(b"partial")
    assert clean_stale(str(tmp_path)) == [] and foreign.exists()
    old = time.time() - FOREIGN_AGE - 60
    os.utime(foreign, (old, old))
    assert clean_stale(str(tmp_path)) == [str(foreign)] and not foreign.exists()


@pytest.mark.parametrize(
    "name, extra",
    [("out.exr", []), ("out.exr", ["--mips"]), ("out.tif", []), ("out.tif", ["--mips"]),
     ("out.hdr", [])],
)  # fmt: skip
def test_full_disk_fails_cleanly(tmp_path, name, extra):
    """EFBIG (RLIMIT_FSIZE, SIGXFSZ ignored) mid-write: exit 1, one line, temp removed, the
    old output intact, never a hang (the timeout fails the test; --mips EXR used to hang)."""
    source = _noise(tmp_path / "noise.exr")
    target = tmp_path / "out" / name
    target.parent.mkdir()
    target.write_bytes(b"old output")
    before = snapshot(source, target)

    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (60_000, 60_000))

    run = envconv("convert", source, target, "--to", "latlong", "--size", 128, *extra,
                  timeout=60, preexec_fn=limit)  # fmt: skip
    assert_failed_cleanly(run, 1, tmp_path, message="cannot write")
    assert ".tmp" not in run.stderr, run.stderr  # the line names the output, not its temp
    assert_untouched(before)


def _big_write(tmp_path):
    source = _noise(tmp_path / "noise.exr")
    out = tmp_path / "out"
    out.mkdir()
    target = out / "big.exr"
    target.write_bytes(b"old output")
    return source, out, target


def test_sigterm_during_a_large_write(tmp_path):
    source, out, target = _big_write(tmp_path)
    before = snapshot(source, target)
    process = _start("convert", source, target, "--to", "latlong", "--size", 1024)
    seconds, stdout, stderr = _signal_after(process, signal.SIGTERM, lambda: litter(out))
    run = Run([], process.returncode, stdout, stderr)
    assert_failed_cleanly(run, 143, tmp_path, message="SIGTERM")
    assert seconds < 2.0, seconds
    assert_untouched(before)


def test_kill_9_during_a_large_write_leaves_a_temp_the_next_run_cleans(tmp_path):
    source, out, target = _big_write(tmp_path)
    before = snapshot(source, target)
    process = _start("convert", source, target, "--to", "latlong", "--size", 1024)
    _signal_after(process, signal.SIGKILL, lambda: litter(out))
    assert process.returncode == -signal.SIGKILL
    assert_untouched(before)
    assert litter(out)  # what kill -9 leaves: only a temp, the old output as it was
    small = envconv("convert", source, out / "small.exr", "--to", "latlong", "--size", 8)
    assert small.returncode == 0 and small.stdout.strip() == str(out / "small.exr"), small.stderr
    assert not litter(tmp_path)
    assert sorted(os.listdir(out)) == ["big.exr", "small.exr"]
    assert_untouched(before)


def test_sigint_during_convert_ends_within_a_second(tmp_path):
    """A long resampling kernel (S = 16 sub-samples per pixel edge) is cancelled between
    bands of rows: exit 130 soon after the signal, nothing written, no temp."""
    source = _noise(tmp_path / "noise.exr")
    target = tmp_path / "out.exr"
    process = _start("convert", source, target, "--to", "latlong", "--size", 1024, "--samples", 16)
    time.sleep(2.0)  # past start-up and reading: in the kernel
    seconds, stdout, stderr = _signal_after(process, signal.SIGINT, lambda: True)
    run = Run([], process.returncode, stdout, stderr)
    assert_failed_cleanly(run, 130, tmp_path, message="SIGINT")
    assert seconds < 2.0, seconds
    assert not target.exists()


def test_sigint_during_batch_cancels_the_queue_and_writes_the_report(tmp_path):
    inputs, out = tmp_path / "in", tmp_path / "out"
    inputs.mkdir()
    sources = [_noise(inputs / f"sky{i}.exr", 32, seed=i) for i in range(12)]
    report = tmp_path / "report.json"
    before = snapshot(*sources)
    process = _start("batch", inputs, "--out", out / "{stem}.exr", "-j", 2, "--report", report,
                     "resample", "--to", "latlong", "--size", 512, "--samples", 4)  # fmt: skip
    first = process.stderr.readline()  # the progress line of the first finished job
    assert " done " in first, first + process.communicate()[1]
    seconds, stdout, stderr = _signal_after(process, signal.SIGINT, lambda: True)
    stderr = first + stderr
    assert process.returncode == 130, stderr
    assert seconds < 2.0, seconds
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert lines[-1] == "envconv: error: interrupted (SIGINT)", lines
    assert "Traceback" not in stderr and stdout == ""
    records = json.loads(report.read_text())["files"]
    done = [r for r in records if r["status"] == "done"]
    cancelled = [r for r in records if r["status"] == "cancelled"]
    assert len(records) == 12 and len(done) + len(cancelled) == 12
    assert 1 <= len(done) <= 6 and len(cancelled) >= 6  # the queue did not run on
    for record in done:
        assert all(os.path.isfile(p) for p in record["outputs"])
    written = set(os.listdir(out))
    finished = {os.path.basename(p) for r in done for p in r["outputs"]}
    assert finished <= written and len(written - finished) <= 2  # at most one per worker
    assert not litter(tmp_path)
    assert_untouched(before)


def test_sigterm_during_an_in_process_batch_writes_the_report(tmp_path):
    """-j 1 runs the jobs in the envconv process itself: SIGTERM mid-job ends it with 143,
    the job running is cancelled with the queue, the report lists what finished."""
    inputs, out, report = tmp_path / "in", tmp_path / "out", tmp_path / "report.json"
    inputs.mkdir()
    for i in range(6):
        _noise(inputs / f"sky{i}.exr", 32, seed=i)
    process = _start("batch", inputs, "--out", out / "{stem}.exr", "--report", report,
                     "resample", "--to", "latlong", "--size", 512, "--samples", 4)  # fmt: skip
    first = process.stderr.readline()
    assert " done " in first, first + process.communicate()[1]
    seconds, stdout, stderr = _signal_after(process, signal.SIGTERM, lambda: True)
    assert process.returncode == 143 and seconds < 2.0, (process.returncode, seconds, stderr)
    assert stderr.splitlines()[-1] == "envconv: error: terminated (SIGTERM)", stderr
    assert "Traceback" not in stderr and stdout == ""
    statuses = [r["status"] for r in json.loads(report.read_text())["files"]]
    assert statuses[0] == "done" and "cancelled" in statuses and "failed" not in statuses
    done = sum(s == "done" for s in statuses)
    written = sorted(os.listdir(out))  # the job stopped may have just renamed its output
    assert written[:done] == [f"sky{i}.exr" for i in range(done)] and len(written) <= done + 1
    assert not litter(tmp_path)


def _constant_inputs(folder, count, ext="exr"):
    folder.mkdir()
    for i in range(count):
        write_plain(folder / f"sky{i:03d}.{ext}", np.full((8, 16, 3), 1 + i / 8, np.float32))


def _worker_pids(pid: int) -> list[int]:
    try:
        children = open(f"/proc/{pid}/task/{pid}/children").read().split()
    except OSError:
        return []
    workers = []
    for child in map(int, children):
        try:
            if b"spawn_main" in open(f"/proc/{child}/cmdline", "rb").read():
                workers.append(child)
        except OSError:
            continue
    return workers


@pytest.mark.skipif(not os.path.exists("/proc/self/task"), reason="needs Linux /proc")
def test_batch_of_100_with_bad_files_and_a_killed_worker(tmp_path):
    """A worker SIGKILLed mid-batch costs only its own job, which runs again on a fresh
    worker; the 5 bad files fail with their own error; every good output is its constant."""
    inputs, out, report = tmp_path / "in", tmp_path / "out", tmp_path / "report.json"
    _constant_inputs(inputs, 100)
    for i in range(5):
        (inputs / f"bad{i}.exr").write_bytes(b"not an image" * i)
    before = snapshot(*inputs.iterdir())
    process = _start("batch", inputs, "--out", out / "{stem}.exr", "-j", 2, "--report", report,
                     "resample", "--to", "cube-vcross", "--size", 4)  # fmt: skip
    victim = _wait_for(lambda: out.is_dir() and len(os.listdir(out)) >= 10
                       and _worker_pids(process.pid))  # fmt: skip
    os.kill(victim[0], signal.SIGKILL)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 1, stderr  # the 5 bad files
    assert stdout.strip().startswith("105 files: 100 done, 0 skipped, 5 failed"), stdout
    assert "Traceback" not in stderr and "BrokenProcessPool" not in stderr
    data = json.loads(report.read_text())
    assert data["summary"]["done"] == 100 and data["summary"]["failed"] == 5
    assert any(f"worker {victim[0]} died (killed by SIGKILL)" in e for e in data["events"])
    failed = [r for r in data["files"] if r["status"] == "failed"]
    assert sorted(os.path.basename(r["input"]) for r in failed) == [f"bad{i}.exr" for i in range(5)]
    assert all(os.path.basename(r["input"]) in r["error"] for r in failed)
    retried = [r for r in data["files"] if r.get("note")]
    assert len(retried) <= 1 and all(r["status"] == "done" for r in retried)
    from envconv import io

    for i in range(100):
        pixels = io.read(out / f"sky{i:03d}.exr").pixels
        filled = pixels[pixels > 0]  # the cross's empty cells hold zeros
        assert filled.size == 6 * 4 * 4 * 3 and np.allclose(filled, 1 + i / 8, rtol=1e-3)
    assert not litter(tmp_path)
    assert_untouched(before)


def test_one_and_two_workers_write_identical_bytes(tmp_path):
    inputs = tmp_path / "in"
    _constant_inputs(inputs, 6, "hdr")  # no DateTime of their own to pass on
    outputs = {}
    for jobs in (1, 2):
        out = tmp_path / f"j{jobs}"
        run = envconv("batch", inputs, "--out", out / "{stem}_{layout}.exr", "-j", jobs,
                      "resample", "--to", "cube-vcross", "--size", 8,
                      "resample", "--to", "octahedral", "--size", 8, "--mips",
                      env={"SOURCE_DATE_EPOCH": "1700000000"})  # fmt: skip
        assert run.returncode == 0, run.stderr
        outputs[jobs] = {name: (out / name).read_bytes() for name in sorted(os.listdir(out))}
        time.sleep(1.05)  # another second: without a fixed date the stamps would differ
    assert len(outputs[1]) == 12 and sorted(outputs[1]) == sorted(outputs[2])
    assert [name for name in outputs[1] if outputs[1][name] != outputs[2][name]] == []


# --- messages: hostile inputs and arguments, exit statuses, library chatter, did-you-mean ---


def _oiio_write(path, pixels, pixel_type="float", attributes=None):
    """An image written by OpenImageIO directly (any pixel type; no envconv tags)."""
    import OpenImageIO as oiio

    height, width, nch = pixels.shape
    spec = oiio.ImageSpec(width, height, nch, getattr(oiio, pixel_type.upper()))
    for name, value in (attributes or {}).items():
        spec.attribute(name, value)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec) and out.write_image(pixels) and out.close()


def _read_back(path):
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(str(path))
    spec = buf.spec()
    return buf.get_pixels(oiio.FLOAT).reshape(spec.height, spec.width, spec.nchannels), spec


def _noise_exr(path, height=32):
    """A zip EXR of noise (it does not compress away, so a cut falls in the pixels)."""
    noise = np.random.default_rng(7).uniform(0, 1, (height, 2 * height, 3)).astype(np.float32)
    _oiio_write(path, noise, attributes={"compression": "zip"})
    return path


def _with_windows(source, target, box):
    """``source`` (an EXR) with both windows rewritten to ``box`` = (xmin, ymin, xmax, ymax)."""
    data = bytearray(source.read_bytes())
    for name in (b"dataWindow\0box2i\0", b"displayWindow\0box2i\0"):
        at = data.index(name) + len(name) + 4
        data[at : at + 16] = struct.pack("<4i", *box)
    target.write_bytes(bytes(data))
    return target


def _convert_fails(tmp_path, source, status, message, *extra):
    """Convert ``source`` and check the clean failure; the input untouched, no output."""
    out = tmp_path / "out" / "o.exr"
    out.parent.mkdir(exist_ok=True)
    before = snapshot(source)
    run = envconv("convert", source, out, "--to", "cube-hstrip", "--size", "4", *extra)
    assert_failed_cleanly(run, status, tmp_path, message=message)
    assert_untouched(before)
    assert not out.exists()
    return run


def _srgb_to_linear(code):
    c = code / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


@pytest.mark.parametrize("kind, message", [
    ("missing", "not found"), ("empty", "cannot read"), ("random", "cannot read"),
    ("truncated", "cannot read"), ("directory", "directory"), ("zero", "cannot read"),
    ("huge", "cannot read"),
])  # fmt: skip
def test_unreadable_inputs_fail_in_one_line(tmp_path, kind, message):
    """Missing, empty, random, truncated, a directory, 0x0 (windows patched: no library
    writes one) and a header claiming 200000x100000: exit 1, one line, nothing on stdout.
    A truncated EXR made OpenEXR print on stdout and stderr before envconv's line."""
    source = tmp_path / "in.exr"
    if kind == "empty":
        source.write_bytes(b"")
    elif kind == "random":
        source.write_bytes(np.random.default_rng(3).bytes(5000))
    elif kind == "truncated":
        data = _noise_exr(tmp_path / "whole.exr").read_bytes()
        source.write_bytes(data[: len(data) * 2 // 3])
    elif kind == "directory":
        source = tmp_path / "folder.exr"
        source.mkdir()
    elif kind in ("zero", "huge"):
        box = (0, 0, -1, -1) if kind == "zero" else (0, 0, 199999, 99999)
        _with_windows(_noise_exr(tmp_path / "whole.exr", 8), source, box)
    _convert_fails(tmp_path, source, 1, message)


def test_truncated_input_in_a_chain_and_in_info_keeps_stdout_clean(tmp_path):
    data = _noise_exr(tmp_path / "whole.exr").read_bytes()
    source = tmp_path / "cut.exr"
    source.write_bytes(data[: len(data) * 2 // 3])
    run = envconv(
        "read", source, "resample", "--to", "latlong", "--size", "4", "write", tmp_path / "o.exr"
    )
    assert_failed_cleanly(run, 1, tmp_path, message="cut.exr")
    assert_failed_cleanly(envconv("info", source, "--stats"), 1, tmp_path, message="cut.exr")
    header = envconv("info", source, "--json")  # the header is whole: info needs no pixel
    assert header.returncode == 0 and header.stderr == "" and '"width": 64' in header.stdout


def test_out_of_memory_is_one_line_exit_1(tmp_path):
    """8192x4096 zip EXR of zeros (200 KB on disk, 400 MB as float) under a 750 MB address
    space: 'out of memory', exit 1 (it was 'internal error: MemoryError', exit 3), for
    convert and info --stats; info alone reads the header and answers."""
    import OpenImageIO as oiio

    limit = 750 * 2**20

    def small_address_space():
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    small = _noise_exr(tmp_path / "small.exr", 8)
    baseline = envconv("convert", small, tmp_path / "s.exr", "--to", "latlong", "--size", "4",
                       preexec_fn=small_address_space)  # fmt: skip
    if baseline.returncode != 0:
        pytest.skip(f"envconv does not start in {limit >> 20} MB here: {baseline.stderr[-200:]}")
    source = tmp_path / "big.exr"
    spec = oiio.ImageSpec(8192, 4096, 3, oiio.HALF)
    spec.attribute("compression", "zip")
    out = oiio.ImageOutput.create(str(source))
    assert out.open(str(source), spec)
    rows = np.zeros((512, 8192, 3), np.float16)
    for y in range(0, 4096, 512):
        assert out.write_scanlines(y, y + 512, 0, rows)
    assert out.close()
    before = snapshot(source)
    run = envconv("convert", source, tmp_path / "o.exr", "--to", "cube-vcross", "--size", "8",
                  preexec_fn=small_address_space)  # fmt: skip
    # Refused by the memory guard from the header ("needs about … of memory and … is
    # available"), or, where the guard let it through, "out of memory": one line, exit 1.
    assert_failed_cleanly(run, 1, tmp_path, message="memory")
    stats = envconv("info", source, "--stats", preexec_fn=small_address_space)
    assert_failed_cleanly(stats, 1, tmp_path, message="memory")
    header = envconv("info", source, "--json", preexec_fn=small_address_space)  # no pixel read
    assert header.returncode == 0 and header.stderr == "" and '"width": 8192' in header.stdout
    assert_untouched(before)


@pytest.mark.parametrize("height, width, message", [
    (1, 1, "--from"), (1, 3, "matches no layout"), (7, 13, "matches no layout"),
])  # fmt: skip
def test_images_no_layout_fits_fail_in_one_line(tmp_path, height, width, message):
    source = tmp_path / "in.exr"
    _oiio_write(source, np.ones((height, width, 3), np.float32))
    _convert_fails(tmp_path, source, 1, message)


def test_a_1x1_image_converts_with_from(tmp_path):
    source, out = tmp_path / "one.exr", tmp_path / "o.exr"
    _oiio_write(source, np.full((1, 1, 3), 0.25, np.float32))
    run = envconv("convert", source, out, "--from", "sphere", "--to", "latlong", "--size", "2")
    assert (run.returncode, run.stdout, run.stderr) == (0, f"{out}\n", "")
    pixels, _ = _read_back(out)
    np.testing.assert_allclose(pixels, 0.25, rtol=1e-3)  # a constant sky stays constant


def test_nan_inf_and_negative_pixels_convert_with_a_warning(tmp_path):
    source, out = tmp_path / "bad.exr", tmp_path / "o.exr"
    pixels = np.full((16, 32, 3), 0.5, np.float32)
    pixels[0, 0, 0], pixels[1, 1, 1], pixels[2, 2, 2] = np.nan, np.inf, -1.0
    _oiio_write(source, pixels)
    before = snapshot(source)
    run = envconv("convert", source, out, "--to", "latlong", "--size", "16")
    assert run.returncode == 0 and run.stdout == f"{out}\n", run.stderr
    assert "Traceback" not in run.stderr and len(run.stderr_lines) == 1
    assert run.stderr_lines[0].startswith("envconv: warning:") and "NaN" in run.stderr_lines[0]
    assert_untouched(before)
    written, _ = _read_back(out)
    assert written.shape == (16, 32, 3)
    assert np.isclose(written[8:, :, :], 0.5).all()  # far from the bad pixels: the sky as it was
    # NaN clamped or kept (--fix-nonfinite none) and negative values kept, not clipped away
    assert np.nanmin(written[..., 2]) < 0


@pytest.mark.parametrize("channels", [1, 2, 4, 5])
def test_any_channel_count_converts(tmp_path, channels):
    source, out = tmp_path / "in.exr", tmp_path / "o.exr"
    values = np.linspace(0.25, 2.0, channels, dtype=np.float32)
    _oiio_write(source, np.ones((8, 16, channels), np.float32) * values)
    run = envconv("convert", source, out, "--to", "cube-hstrip", "--size", "4")
    assert (run.returncode, run.stdout, run.stderr) == (0, f"{out}\n", "")
    written, spec = _read_back(out)
    assert spec.nchannels == channels
    np.testing.assert_allclose(written.reshape(-1, channels).min(0), values, rtol=1e-3)
    np.testing.assert_allclose(written.reshape(-1, channels).max(0), values, rtol=1e-3)


@pytest.mark.parametrize("name, pixel_type, code, expected", [
    ("in.exr", "half", 0.75, 0.75),
    ("in.png", "uint8", 128, _srgb_to_linear(128)),
    ("in.tif", "uint16", 30000, _srgb_to_linear(30000 / 65535 * 255)),
])  # fmt: skip
def test_half_uint8_and_uint16_inputs_convert(tmp_path, name, pixel_type, code, expected):
    """Integer files are sRGB-encoded by default (docs/color.md): the EXR written holds the
    decoded linear value."""
    source, out = tmp_path / name, tmp_path / "o.exr"
    dtype = {"half": np.float16, "uint8": np.uint8, "uint16": np.uint16}[pixel_type]
    _oiio_write(source, np.full((8, 16, 3), code, dtype), pixel_type)
    run = envconv("convert", source, out, "--to", "cube-hstrip", "--size", "4")
    assert (run.returncode, run.stdout, run.stderr) == (0, f"{out}\n", "")
    written, _ = _read_back(out)
    np.testing.assert_allclose(written, expected, rtol=2e-3)


def test_a_png_named_exr_is_read_by_its_content(tmp_path):
    source, out = tmp_path / "photo.exr", tmp_path / "o.exr"
    _oiio_write(tmp_path / "photo.png", np.full((8, 16, 3), 200, np.uint8), "uint8")
    (tmp_path / "photo.png").rename(source)
    run = envconv("convert", source, out, "--to", "cube-hstrip", "--size", "4")
    assert (run.returncode, run.stdout, run.stderr) == (0, f"{out}\n", "")
    np.testing.assert_allclose(_read_back(out)[0], _srgb_to_linear(200), rtol=2e-3)


def test_unicode_paths(tmp_path):
    source, out = tmp_path / "ciel étoilé ☀.exr", tmp_path / "sortie 出力" / "立方体 ü.exr"
    out.parent.mkdir()
    _oiio_write(source, np.full((8, 16, 3), 0.5, np.float32))
    run = envconv("convert", source, out, "--to", "cube-hstrip", "--size", "4")
    assert (run.returncode, run.stdout, run.stderr) == (0, f"{out}\n", "")
    np.testing.assert_allclose(_read_back(out)[0], 0.5, rtol=1e-3)


@pytest.mark.parametrize("where", ["under-a-file", "proc"])
def test_an_output_folder_that_cannot_exist_fails_in_one_line(tmp_path, where):
    """Tests run as root in CI, where chmod does not stop a write: the folder is a regular
    file's path (cannot be created) or under /proc (no files can be made there)."""
    source = _noise_exr(tmp_path / "in.exr", 8)
    out = source / "o.exr" if where == "under-a-file" else "/proc/envconv-hostile/o.exr"
    before = snapshot(source)
    run = envconv("convert", source, out, "--to", "cube-hstrip", "--size", "4")
    assert_failed_cleanly(run, 1, tmp_path, message="cannot write")
    assert_untouched(before)


@pytest.mark.parametrize("args, message", [
    (["--size", "0"], "--size"), (["--size", "-5"], "--size"),
    (["--samples", "0"], "--samples"), (["--samples", "1000"], "--samples"),
    (["--compression", "lzma"], "compression"), (["--bit-depth", "uint8"], "uint8"),
    (["--out-convention", "nope"], "convention"),
])  # fmt: skip
def test_bad_option_values_are_usage_errors(tmp_path, args, message):
    """Exit 2 whether click or envconv finds the problem (envconv's own exited 1)."""
    source = _noise_exr(tmp_path / "in.exr", 8)
    _convert_fails(tmp_path, source, 2, message, *args)


def test_an_unknown_output_extension_is_a_usage_error(tmp_path):
    source = _noise_exr(tmp_path / "in.exr", 8)
    before = snapshot(source)
    run = envconv("convert", source, tmp_path / "o.xyz", "--to", "latlong", "--size", "4")
    assert_failed_cleanly(run, 2, tmp_path, message="unknown extension .xyz")
    assert_untouched(before)
    assert not (tmp_path / "o.xyz").exists()


def test_missing_to_lists_the_layouts(tmp_path):
    source = _noise_exr(tmp_path / "in.exr", 8)
    run = envconv("convert", source, tmp_path / "o.exr")
    assert_failed_cleanly(run, 2, tmp_path, message="missing option '--to'")
    assert "latlong, cube-vcross" in run.stderr and "equal-area" in run.stderr


@pytest.mark.parametrize("chain, typo, meant", [
    (["resampel", "--to", "latlong"], "resampel", "resample"),
    (["resampel", "write", "o.exr"], "resampel", "resample"),
    (["resample", "--to", "latlong", "wirte", "o.exr"], "wirte", "write"),
])  # fmt: skip
def test_a_misspelt_step_is_named(tmp_path, chain, typo, meant):
    source = _noise_exr(tmp_path / "in.exr", 8)
    run = envconv("read", source, *chain, cwd=tmp_path)
    assert_failed_cleanly(
        run, 2, tmp_path, message=f"no such command '{typo}'; did you mean '{meant}'?"
    )
    run = envconv(typo, cwd=tmp_path)
    assert_failed_cleanly(run, 2, tmp_path, message=f"did you mean '{meant}'?")


@pytest.mark.parametrize("name, message", [
    ("latlng", "did you mean 'latlong'?"), ("cube-vcros", "did you mean 'cube-vcross'"),
    ("cubemap", "cube-vcross, cube-hcross, cube-hstrip, cube-vstrip, cube-exr, cube-faces"),
    ("equirectangle", "did you mean 'latlong'?"),
])  # fmt: skip
def test_layout_typos_and_families_are_answered(tmp_path, name, message):
    source = _noise_exr(tmp_path / "in.exr", 8)
    _convert_fails(tmp_path, source, 2, message, "--from", name)


@pytest.mark.parametrize("alias", ["equirect", "equirectangular", "EQUIRECT"])
def test_equirect_aliases_are_latlong(tmp_path, alias):
    source = _noise_exr(tmp_path / "in.exr", 8)
    out = tmp_path / "{layout}.exr"  # the name the layout was given its registered name by
    run = envconv(
        "read", source, "--from", alias, "resample", "--to", alias, "--size", "8", "write", out
    )
    assert (run.returncode, run.stdout, run.stderr) == (0, f"{tmp_path / 'latlong.exr'}\n", "")
    written, spec = _read_back(tmp_path / "latlong.exr")
    assert spec.get_string_attribute("envconv:layout") == "latlong"
    np.testing.assert_allclose(written, _read_back(source)[0], atol=1e-6)  # same size: the same map


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_a_truncated_file_in_a_batch_prints_nothing_of_the_libraries(tmp_path, jobs):
    """In the workers too, OpenEXR's lines are caught: the failed file's report line carries
    them, nothing else reaches stderr and stdout holds only the summary."""
    folder = tmp_path / "in"
    folder.mkdir()
    _noise_exr(folder / "good.exr", 8)
    data = _noise_exr(tmp_path / "whole.exr").read_bytes()
    (folder / "cut.exr").write_bytes(data[: len(data) * 2 // 3])
    run = envconv("-v", "batch", folder, "-j", jobs, "resample", "--to", "latlong", "--size", "4",
                  "write", tmp_path / "out" / "{stem}.exr")  # fmt: skip
    assert run.returncode == 1 and "Traceback" not in run.stderr
    assert all(line.startswith("envconv:") for line in run.stderr_lines), run.stderr
    assert "EXR_ERR" not in run.stdout and "Warning" not in run.stdout, run.stdout
    assert len(run.stdout.splitlines()) == 1 and "1 failed" in run.stdout
    (failed,) = [line for line in run.stderr_lines if "cut.exr" in line]
    assert "failed" in failed and "EXR_ERR" in failed  # OpenEXR's reason, folded in
    assert (tmp_path / "out" / "good.exr").is_file() and not (tmp_path / "out" / "cut.exr").exists()
    assert not litter(tmp_path)


@pytest.mark.parametrize("output", ["o.png", "o_{face}.jpg", "o.tif"])
def test_nan_to_an_integer_format_prints_envconv_lines_only(tmp_path, output):
    """numpy's RuntimeWarning (two lines: message and source) came out of the dither."""
    source = tmp_path / "bad.exr"
    pixels = np.full((16, 32, 3), 0.5, np.float32)
    pixels[0, 0, 0], pixels[1, 1, 1] = np.nan, np.inf
    _oiio_write(source, pixels)
    layout = "cube-faces" if "{face}" in output else "latlong"
    run = envconv("convert", source, tmp_path / output, "--to", layout, "--size", "8",
                  "--bit-depth", "uint8")  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert run.stderr_lines and all(
        line.startswith("envconv: warning: ") for line in run.stderr_lines
    ), run.stderr
    assert "RuntimeWarning" not in run.stderr


# --- contradicting options: exit 2 before any work (docs/shell.md, exit statuses) ---------------
# Each case runs on an input whose header is whole and whose pixels are cut off: reading a
# pixel would fail with status 1 ("cannot read"), so status 2 with the contradiction's message
# proves that it was found first, from arguments and headers alone; nothing is written.


def _cut_pixels(tmp_path):
    data = _noise_exr(tmp_path / "whole.exr", 16).read_bytes()
    source = tmp_path / "cut.exr"
    source.write_bytes(data[: len(data) * 2 // 3])
    (tmp_path / "whole.exr").unlink()
    return source


@pytest.mark.parametrize("out, args, message", [
    ("o.exr", ["--mips", "3", "--size", "8"], "all 5 levels"),     # OpenEXR holds full chains
    ("o.exr", ["--mips", "3"], "levels down to 1x1"),              # (size from the header)
    ("o.png", ["--mips"], "png holds one image"),                  # a chain needs {level}
    ("o.jpg", ["--mips", "2", "--size", "8"], "put {level} in the path"),
    ("o.hdr", ["--mips", "ggx"], "hdr holds one image"),
    ("o.dds", ["--to", "cube-hcross", "--guard", "2"], "no guard ring"),
    ("o.ktx2", ["--to", "paraboloid-split"], "one image or one cube"),
    ("o.exr", ["--output-colorspace", "no-such-space"], "unknown colour space"),
    ("o.exr", ["--input-colorspace", "no-such-space"], "unknown colour space"),
    ("o.exr", ["--out-convention", "ddgi"], "applies to octahedral"),
    ("o.exr", ["--in-convention", "ddgi"], "applies to octahedral"),   # the header's latlong
    ("o_{face}.exr", ["--to", "cube-faces", "--out-convention", "openexr", "--mips"],
     "moves cells"),
    ("o.exr", ["--up", "z", "--axes", "x,y,z"], "not both"),
])  # fmt: skip
def test_contradicting_options_exit_2_before_any_work(tmp_path, out, args, message):
    """In this process (click's runner: the same group, exit statuses and streams) to keep
    the thirteen cases cheap; the chain, batch and graph cases below run the console script."""
    source = _cut_pixels(tmp_path)
    to = [] if "--to" in args else ["--to", "latlong"]
    size = [] if "--size" in args or "--mips" in args else ["--size", "8"]
    result = run_cli(["convert", source, tmp_path / out, *to, *size, *args])
    run = Run([], result.exit_code, result.stdout, result.stderr)
    assert_failed_cleanly(run, 2, tmp_path, message=message)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cut.exr"]


def test_the_cut_input_fails_as_a_read_without_a_contradiction(tmp_path):
    """The control for the cases above: the same input and arguments without the
    contradiction read pixels and fail with status 1."""
    source = _cut_pixels(tmp_path)
    run = envconv("convert", source, tmp_path / "o_{level}.png", "--to", "latlong", "--mips")
    assert_failed_cleanly(run, 1, tmp_path, message="cannot read")


@pytest.mark.parametrize("command", ["chain", "batch", "graph"])
def test_a_chain_a_batch_and_a_graph_file_refuse_a_contradiction_before_any_job(tmp_path,
                                                                                 command):  # fmt: skip
    source = _cut_pixels(tmp_path)
    if command == "chain":
        run = envconv("read", source, "resample", "--to", "sphere", "--mips", "write",
                      tmp_path / "o.png")  # fmt: skip
    elif command == "batch":
        run = envconv("batch", source, "--out", str(tmp_path / "o.png"), "resample", "--to",
                      "sphere", "--mips")  # fmt: skip
    else:
        graph = tmp_path / "g.toml"
        graph.write_text('inputs = ["cut.exr"]\n[[steps]]\nstep = "resample"\nto = "sphere"\n'
                         'mips = true\n[[steps]]\nstep = "write"\npath = "o.png"\n')  # fmt: skip
        run = envconv("run", graph)
    assert_failed_cleanly(run, 2, tmp_path, message="png holds one image")
    assert not (tmp_path / "o.png").exists()


def test_batch_workers_that_cannot_start_stop_the_batch_in_one_line(tmp_path):
    """A broken environment that only the spawned workers meet (a sitecustomize that exits in
    a process started with --multiprocessing-fork): every worker would die on start, so the
    batch stops at once with one line quoting the worker's error, exit 1, nothing written."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text(
        "import sys\nif '--multiprocessing-fork' in sys.argv:\n"
        "    raise SystemExit('simulated: this environment cannot run a worker')\n")  # fmt: skip
    folder = tmp_path / "in"
    folder.mkdir()
    maps = [_map(folder / "a.exr"), _map(folder / "b.exr")]
    before = snapshot(*maps)
    path = os.pathsep.join(p for p in (str(site), os.environ.get("PYTHONPATH", "")) if p)
    run = envconv("batch", folder, "--out", tmp_path / "out" / "{stem}.exr", "-j", "2",
                  "resample", "--to", "latlong", "--size", "4", env={"PYTHONPATH": path},
                  timeout=60)  # fmt: skip
    assert_failed_cleanly(run, 1, tmp_path, message="batch workers cannot start")
    assert "simulated: this environment cannot run a worker" in run.stderr
    assert not (tmp_path / "out").exists()
    assert_untouched(before)


# --- processes, arguments and library use (issue 27, second half) ----------------------------
# Truth: exit statuses and the one line the issue asks for, the files on disk (nothing written
# where a run is refused), real symlink cycles, a fake /sys/fs/cgroup tree whose numbers are
# written by the test, real signals, and outputs compared with envconv.convert of the input.


@pytest.mark.parametrize("args, message", [
    (["--level", "100000000000000000000"], "--level"), (["--exposure", "1e308"], "--exposure"),
    (["--exposure", "nan"], "--exposure"), (["--size", "100000000000000000000"], "--size"),
    (["--roughness", "foo"], "--roughness"), (["--roughness", "0.5,2"], "--roughness"),
])  # fmt: skip
def test_numbers_no_image_can_have_are_usage_errors(tmp_path, args, message):
    """They reached OpenImageIO (an int overflow), 2**1e308 or the memory guard's figures and
    ended in exit 3 ('internal error') or a 33-digit number of gigabytes."""
    source = _noise_exr(tmp_path / "in.exr", 8)
    _convert_fails(tmp_path, source, 2, message, *args)


@pytest.mark.parametrize("args, message", [
    (["--threads", "100000000000000000000", "convert", "{src}", "{out}", "--to", "latlong"],
     "--threads"),
    (["read", "{src}", "--level", "1e20", "resample", "--to", "latlong", "write", "{out}"],
     "--level"),
    (["read", "{src}", "exposure", "1e308", "resample", "--to", "latlong", "write", "{out}"],
     "exposure"),
    (["info", "{src}", "--level", "100000000000000000000"], "--level"),
    (["pattern", "{out}", "--to", "latlong", "--size", "100000000000000000000"], "--size"),
])  # fmt: skip
def test_numbers_in_chains_and_other_commands_are_usage_errors(tmp_path, args, message):
    source = _noise_exr(tmp_path / "in.exr", 8)
    out = tmp_path / "o.exr"
    run = envconv(*[a.format(src=source, out=out) for a in args])
    assert_failed_cleanly(run, 2, tmp_path, message=message)
    assert not out.exists()


def _graph_with(tmp_path, name: str, resample_extra: str = "", first: str = "") -> str:
    """A graph file resampling sky.exr, with ``resample_extra`` (TOML or JSON members) added."""
    if name.endswith(".json"):
        first = first or ""
        return ('{"inputs": ["sky.exr"], "steps": [' + first + '{"step": "resample", '
                '"to": "latlong", "size": 8' + resample_extra + '}, '
                '{"step": "write", "path": "{stem}_out.exr"}]}')  # fmt: skip
    return ('inputs = ["sky.exr"]\n' + first + '[[steps]]\nstep = "resample"\nto = "latlong"\n'
            + resample_extra + '\n[[steps]]\nstep = "write"\npath = "{stem}_out.exr"\n')  # fmt: skip


_DEEP = 100_000


@pytest.mark.parametrize("name, extra, first, message", [
    ("g.json", ', "roughness": ' + "[" * _DEEP + "]" * _DEEP, "", "nested"),
    ("g.toml", "roughness = " + "[" * _DEEP + "]" * _DEEP, "", "nested"),
    ("g.toml", "roughness = " + "[" * 40 + "]" * 40, "", "nested"),
    ("g.json", ', "guard": ' + "9" * 5000, "", "too large"),
    ("g.toml", "size = " + "9" * 5000, "", "too large"),
    ("g.toml", "size = " + "9" * 4000, "", "too large"),
    ("g.toml", "size = 100000000000000000000", "", "size"),
    ("g.toml", "size = 4194304", "", "size"),
    ("g.toml", 'mips = "ggx"\nroughness = "foo"', "", "roughness"),
    ("g.toml", "roughness = [0.5, 2.0]", "", "roughness"),
    ("g.toml", "", '[[steps]]\nstep = "read"\nlevel = 100000000000000000000\n', "level"),
    ("g.toml", "", '[[steps]]\nstep = "read"\nlevel = 32\n', "level"),
    ("g.toml", "", '[[steps]]\nstep = "exposure"\nstops = 1e308\n', "stops"),
    ("g.toml", "", '[[steps]]\nstep = "read"\nexposure = -1e300\n', "exposure"),
])  # fmt: skip
def test_graph_files_are_refused_before_any_job(tmp_path, name, extra, first, message):
    """A graph nested 100 000 deep (RecursionError), a 5000-digit integer (ValueError of
    Python's int limit), numbers no image can have and an unknown roughness: exit 2 with one
    short line naming the file, before any job ran (``roughness = "foo"`` passed validation
    and failed the job later, exit 1)."""
    _map(tmp_path / "sky.exr")
    graph = tmp_path / name
    graph.write_text(_graph_with(tmp_path, name, extra, first))
    run = envconv("run", graph)
    assert_failed_cleanly(run, 2, tmp_path, message=message)
    assert name in run.stderr and len(run.stderr) < 400, run.stderr
    assert sorted(os.listdir(tmp_path)) == sorted([name, "sky.exr"])


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("args", [
    ["convert", "{src}", "{out}", "--to", "latlong", "--size", "4"],
    ["read", "{src}", "resample", "--to", "latlong", "--size", "4", "write", "{out}"],
    ["info", "{src}"], ["info", "{src}", "--json"], ["layouts"], ["--help"], ["--version"],
    ["convert", "{src}", "{out}", "--to", "latlong", "--dry-run"],
    ["batch", "{src}", "--out", "{out}", "resample", "--to", "latlong", "--size", "4"],
])  # fmt: skip
def test_stdout_on_dev_full_is_one_line_exit_1(tmp_path, args):
    """Results on a stdout that takes nothing: 'cannot write to stdout', exit 1 (was exit 3,
    an internal OSError, or a traceback for --help)."""
    source = _noise_exr(tmp_path / "in.exr", 8)
    argv = [ENVCONV, *(a.format(src=source, out=tmp_path / "o.exr") for a in args)]
    with open("/dev/full", "w") as full:
        done = subprocess.run(argv, stdout=full, stderr=subprocess.PIPE, text=True, timeout=60)
    progress = [line for line in done.stderr.splitlines() if line.startswith("envconv: [")]
    assert len(progress) == (1 if "batch" in args else 0), done.stderr  # batch's "[1/1] done"
    errors = "".join(f"{line}\n" for line in done.stderr.splitlines() if line not in progress)
    run = Run(argv, done.returncode, "", errors)
    assert_failed_cleanly(run, 1, tmp_path, message="cannot write to stdout: No space left")


def _cyclic_tree(root):
    """tree/a/b/sky.exr under three links back up (a cycle Python's glob walks 3^40 ways),
    a link to a folder outside the tree (itself holding a link to itself) and a link to a
    file; tree/.hidden/ and a dangling link are not inputs."""
    tree, library = root / "tree", root / "library"
    (tree / "a" / "b").mkdir(parents=True)
    library.mkdir()
    (tree / ".hidden").mkdir()
    _map(tree / "a" / "b" / "sky.exr", 1.0)
    _map(library / "far.exr", 2.0)
    _map(tree / ".hidden" / "secret.exr", 3.0)
    for name, target in (("up", ".."), ("top", "../.."), ("again", "../../a")):
        os.symlink(target, tree / "a" / "b" / name)
    os.symlink("../library", tree / "lib")
    os.symlink("../library", library / "self")
    os.symlink("a/b/sky.exr", tree / "near.exr")
    os.symlink("missing", tree / "dangling")
    return tree


def test_a_recursive_glob_over_a_link_cycle_ends(tmp_path):
    """``tree/**/*.exr`` followed the cycle's links until the paths grew too long, 3 ways at
    each level: it never returned. Each real folder is walked once; a link to a file or a
    folder counts, under its first name."""
    tree = _cyclic_tree(tmp_path)
    report = tmp_path / "report.json"
    run = envconv("batch", f"{tree}/**/*.exr", "--out", tmp_path / "out" / "{stem}.exr",
                  "--report", report, "resample", "--to", "latlong", "--size", 4,
                  timeout=60)  # fmt: skip
    assert run.returncode == 0, run.stderr
    inputs = [r["input"] for r in json.loads(report.read_text())["files"]]
    assert inputs == [str(tree / "a/b/sky.exr"), str(tree / "lib/far.exr"), str(tree / "near.exr")]
    assert sorted(os.listdir(tmp_path / "out")) == ["far.exr", "near.exr", "sky.exr"]
    from envconv import io

    assert np.allclose(io.read(tmp_path / "out" / "far.exr").pixels, 2.0, rtol=1e-3)


def test_a_v1_memory_cgroup_limit_refuses_before_allocating(tmp_path):
    """In a v1 memory cgroup (1 GiB here, a fake /sys/fs/cgroup tree) the guard read only v2's
    memory.max and MemAvailable (64 GiB here): an over-large run went on and was OOM-killed
    with no message. Now: one line naming the memory, exit 1, nothing written."""
    from test_memory import _V1_MOUNTS, _V1_UNLIMITED, cgroup_tree

    group = "/sys/fs/cgroup/memory/jobs/run7/"
    root = cgroup_tree(tmp_path / "system", "4:memory:/jobs/run7\n0::/\n", _V1_MOUNTS.format(root="/"), {
        group + "memory.limit_in_bytes": f"{64 << 20}\n",
        group + "memory.usage_in_bytes": f"{20 << 20}\n",
        "/sys/fs/cgroup/memory/memory.limit_in_bytes": f"{_V1_UNLIMITED}\n",
    })  # fmt: skip
    source, out = _map(tmp_path / "sky.exr"), tmp_path / "out" / "o.exr"
    code = ("import sys; import envconv.engine.memory as m; m.SYSTEM_ROOT = sys.argv.pop(1); "
            "from envconv.cli import main; main()")  # fmt: skip
    argv = [sys.executable, "-c", code, root, "convert", str(source), str(out), "--to",
            "cube-vcross", "--size", "1024"]  # fmt: skip
    env = {k: v for k, v in os.environ.items() if k != "ENVCONV_MEMORY_LIMIT"}
    done = subprocess.run(argv, capture_output=True, text=True, timeout=120, env=env)
    run = Run(argv, done.returncode, done.stdout, done.stderr)
    assert_failed_cleanly(run, 1, tmp_path, message="of memory and")
    assert "available" in run.stderr and not out.exists()


def _before_envconv_ran(stderr: str) -> bool:
    """A traceback of Python's own KeyboardInterrupt (not envconv's ``Interrupted``) from a
    signal that came before envconv had a handler: while Python started, loaded the envconv
    package or ran the first lines of envconv/__main__.py, which install it. Out of any
    program's reach (docs/shell.md); anywhere later it is a failure."""
    lines = stderr.strip().splitlines()
    if not lines or not re.fullmatch(r"KeyboardInterrupt:?", lines[-1].strip()):
        return False
    frames = re.findall(r'File "([^"]+)", line \d+, in (\S+)', stderr)
    early = ("__init__.py", "errors.py")
    for path, function in frames:
        if not re.search(r"[/\\]envconv[/\\]", path):
            continue
        name = re.split(r"[/\\]", path)[-1]
        if name not in early and not (name == "__main__.py" and function.startswith("<")):
            return False
    return True


def test_sigint_at_any_early_moment_is_one_line_or_nothing(tmp_path):
    """Ctrl-C in the first 50 ms (Python starting, click and the commands loading, the first
    read) printed a KeyboardInterrupt traceback, or aborted with SIGABRT when it landed in
    OpenImageIO's module initialisation. Now: exit 130 (or killed by SIGINT, before Python
    took the signal over), nothing on stdout, at most the one line, never a temp."""
    source = _noise_exr(tmp_path / "in.exr", 8)
    early, handled = [], 0
    for delay in [i / 1000 for i in range(0, 52, 6)] + [0.1, 0.25, 0.5]:
        process = _start("convert", source, tmp_path / "o.exr", "--to", "latlong", "--size", 64)
        time.sleep(delay)
        sent = time.monotonic()
        try:
            os.killpg(process.pid, signal.SIGINT)
        except ProcessLookupError:  # it has ended already: its streams say how
            pass
        stdout, stderr = process.communicate(timeout=60)
        seconds = time.monotonic() - sent
        if _before_envconv_ran(stderr):
            early.append(delay)
            continue
        assert "Traceback" not in stderr and "Fatal" not in stderr, (delay, stderr)
        lines = [line for line in stderr.splitlines() if line.strip()]
        if process.returncode == 0:  # the run ended before the signal: it is whole
            assert stdout == f"{tmp_path / 'o.exr'}\n" and not lines, (delay, stderr)
            continue
        assert process.returncode in (130, -signal.SIGINT), (delay, process.returncode, stderr)
        assert lines in ([], ["envconv: error: interrupted (SIGINT)"]), (delay, stderr)
        # Nothing on stdout, or (the signal cut short the ending of a finished run) all of it.
        assert stdout in ("", f"{tmp_path / 'o.exr'}\n"), (delay, stdout)
        assert seconds < 2.0 and not litter(tmp_path), (delay, seconds)
        handled += bool(lines)
    assert handled, early  # some signals reached envconv, however slow the machine


def test_kill_9_of_the_batch_parent_ends_its_workers_quietly(tmp_path):
    """SIGKILL of ``envconv batch -j 2``: each worker finished its job for no one and printed
    a BrokenPipeError traceback. Now they stop at once (SIGTERM from Linux at the parent's
    death), remove their temps and end; the batch's own streams hold nothing."""
    inputs, out = tmp_path / "in", tmp_path / "out"
    inputs.mkdir()
    for i in range(4):
        _noise(inputs / f"sky{i}.exr", 32, seed=i)
    process = _start("batch", inputs, "--out", out / "{stem}.exr", "-j", 2,
                     "resample", "--to", "latlong", "--size", 1024, "--samples", 16)  # fmt: skip

    def stat(pid: int) -> list[str]:
        try:
            return open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
        except OSError:
            return []

    def ended(pid: int) -> bool:  # gone, or a zombie until init reaps it
        return stat(pid)[:1] in ([], ["Z"])

    def busy(pid: int) -> bool:  # past start-up (~1 s of CPU), into its first job (~8 s)
        fields = stat(pid)
        return bool(fields) and (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK") > 2

    workers: list[int] = []
    try:
        workers = _wait_for(
            lambda: len(_worker_pids(process.pid)) == 2 and _worker_pids(process.pid)
        )
        _wait_for(lambda: all(busy(pid) for pid in workers), timeout=120)
        os.kill(process.pid, signal.SIGKILL)
        killed = time.monotonic()
        stdout, stderr = process.communicate(timeout=60)  # the workers hold its stdout too
        _wait_for(lambda: all(ended(pid) for pid in workers), timeout=5.0)
        assert time.monotonic() - killed < 5.0  # not the rest of a job (~6 s of CPU)
    finally:
        for pid in workers:
            if not ended(pid):
                os.kill(pid, signal.SIGKILL)
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()
    assert stdout == "" and stderr == "", stderr
    assert not litter(tmp_path)


def test_two_threads_of_a_library_caller_keep_their_output(tmp_path, capfd, monkeypatch):
    """envconv.read/write pointed descriptors 1 and 2 at a file of their own while they ran:
    what another thread of the caller printed meanwhile (a Dask worker's other task, its
    logging) went into that file and was lost. Now a library call touches no descriptor:
    thread A is held inside a read's OpenImageIO open while thread B prints and runs its own
    read, convert and write; every line reaches the real descriptors and every output is
    the conversion of its input."""
    import threading

    import envconv
    from envconv.io import files

    sources = [_map(tmp_path / f"sky{i}.exr", 1.0 + i) for i in range(2)]
    inside, printed = threading.Event(), threading.Event()
    oiio = files._oiio()

    class HeldOpen:  # OpenImageIO, with thread A's first open held until B has printed
        def __getattr__(self, name):
            return getattr(oiio, name)

        class ImageInput:
            @staticmethod
            def open(*args):
                if threading.current_thread().name == "A" and not inside.is_set():
                    inside.set()
                    assert printed.wait(30)
                return oiio.ImageInput.open(*args)

    monkeypatch.setattr(files, "_oiio", HeldOpen)
    errors = []

    def work(index):
        try:
            if index == 1:
                assert inside.wait(30)
                os.write(1, b"B: out\n")
                os.write(2, b"B: err\n")
                print("B: print", flush=True)
                printed.set()
            sky = envconv.read(sources[index], threads=1)
            cube = envconv.convert(sky, "cube-vcross", size=8, threads=1 + index)
            envconv.write(cube, tmp_path / f"out{index}.exr")
        except BaseException as exc:  # reported by the main thread
            errors.append(exc)
            printed.set()

    threads = [threading.Thread(target=work, args=(i,), name="AB"[i]) for i in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    assert not errors, errors
    out, err = capfd.readouterr()
    assert out.splitlines() == ["B: out", "B: print"] and err.splitlines() == ["B: err"], (out, err)
    for index in range(2):
        written = envconv.read(tmp_path / f"out{index}.exr").pixels
        filled = written[written > 0]
        assert filled.size == 6 * 8 * 8 * 3 and np.allclose(filled, 1.0 + index, rtol=1e-3)


# --- files and outputs, second round (issue 27): writers' results, the report, final names, ---
# sets replaced whole, temp locks, exit 3s that were due a one-line 1 or 2, late checks.
# Truth: the bytes of inputs and old outputs (snapshots taken before the run), the exit status
# and the one line, the folder listings, and the pixels read back against the constant each
# input held.


def _fsize_limit(limit: int):
    """preexec_fn: a "full disk" at ``limit`` bytes per file (EFBIG; SIGXFSZ ignored)."""

    def apply():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return apply


@pytest.mark.parametrize("command, name", [
    ("convert", "o.png"), ("convert", "o.jpg"), ("convert", "o.tga"), ("preview", "o.png"),
    ("preview", "o.jpg"),
])  # fmt: skip
def test_a_full_disk_fails_png_and_jpeg_writes(tmp_path, command, name):
    """libpng reported EFBIG only through geterror (write and close said True: exit 0 and a
    cut PNG renamed over the old file); libjpeg called exit(1) (empty stderr, temp left);
    OpenImageIO's TGA writer ignored it (exit 0, an 18-byte file renamed over the old one)."""
    source = _noise(tmp_path / "noise.exr")
    target = tmp_path / "out" / name
    target.parent.mkdir()
    target.write_bytes(b"old output")
    before = snapshot(source, target)
    args = {"convert": ["convert", source, target, "--to", "latlong", "--size", 256],
            "preview": ["preview", source, "-o", target]}[command]  # fmt: skip
    run = envconv(*args, timeout=60, preexec_fn=_fsize_limit(40_000))
    assert_failed_cleanly(run, 1, tmp_path, message=f"cannot write {target}")
    assert_untouched(before)


def test_a_full_disk_fails_the_batch_job_that_writes_a_png(tmp_path):
    source = _noise(tmp_path / "noise.exr")
    out, report = tmp_path / "out", tmp_path / "report.json"
    out.mkdir()
    (out / "noise.png").write_bytes(b"old output")
    before = snapshot(source, out / "noise.png")
    run = envconv("batch", source, "--out", out / "{stem}.png", "--report", report, "resample",
                  "--to", "latlong", "--size", 256, preexec_fn=_fsize_limit(40_000))  # fmt: skip
    assert run.returncode == 1 and "1 failed" in run.stdout, (run.stdout, run.stderr)
    (record,) = json.loads(report.read_text())["files"]
    assert record["status"] == "failed" and "cannot write" in record["error"], record
    assert not litter(tmp_path)
    assert_untouched(before)


def _graph(tmp_path, write_path="o_{stem}.exr"):
    graph = tmp_path / "g.toml"
    graph.write_text('inputs = ["sky.exr"]\n[[steps]]\nstep = "resample"\nto = "latlong"\n'
                     f'size = 8\n[[steps]]\nstep = "write"\npath = "{write_path}"\n')  # fmt: skip
    return graph


@pytest.mark.parametrize("case, message", [
    ("graph", "g.toml is the input"), ("input", "sky.exr is the input"),
    ("output", "and --report would both write"), ("under-a-file", "sky.exr is a file, not a folder"),
    ("folder", "folder.json is a folder"), ("no-clobber", "old.json exists and -n"),
])  # fmt: skip
def test_the_report_path_goes_through_the_output_policy(tmp_path, case, message):
    """--report is an output like any other: never an input (the graph file included), never
    another output, refused with -n when it exists; a path that cannot be written is refused
    before any job runs (it failed after all of them, or replaced the file named)."""
    source = _map(tmp_path / "sky.exr")
    graph = _graph(tmp_path)
    out = tmp_path / "out"
    (tmp_path / "folder.json").mkdir()
    (tmp_path / "old.json").write_text("{}")
    report = {"graph": graph, "input": source, "output": out / "sky.exr",
              "under-a-file": source / "r.json", "folder": tmp_path / "folder.json",
              "no-clobber": tmp_path / "old.json"}[case]  # fmt: skip
    before = snapshot(source, graph, tmp_path / "old.json")
    if case == "graph":
        run = envconv("run", graph, "--report", report)
    else:
        extra = ["-n"] if case == "no-clobber" else []
        run = envconv("batch", source, *extra, "--out", out / "{stem}.exr", "--report", report,
                      "resample", "--to", "latlong", "--size", 8)  # fmt: skip
    _refused(run, tmp_path, message=message)
    assert_untouched(before)
    assert not out.exists() and not (tmp_path / "o_sky.exr").exists()  # no job ran


def test_report_dash_writes_the_json_on_stdout(tmp_path):
    source = _map(tmp_path / "sky.exr")
    run = envconv("batch", source, "--out", tmp_path / "out" / "{stem}.exr", "--report", "-",
                  "resample", "--to", "latlong", "--size", 8, cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)  # stdout holds the report alone; the summary is on stderr
    assert [r["status"] for r in data["files"]] == ["done"]
    assert run.stderr_lines[-1].startswith("1 files: 1 done"), run.stderr
    assert not (tmp_path / "-").exists()
    both = envconv("batch", source, "--out", tmp_path / "out" / "{stem}.exr", "--report", "-",
                   "--json", "resample", "--to", "latlong", "--size", 8)  # fmt: skip
    assert_failed_cleanly(both, 2, tmp_path, message="--report - and --json")


def test_braces_in_an_input_name_stay_literal_in_outputs(tmp_path):
    """a0.exr and a{level}.exr were both "done" into out/a0.exr: the {level} of the second
    input's stem was expanded as the output's own. Each input gets its own file, whose pixels
    are that input's constant."""
    folder, out = tmp_path / "in", tmp_path / "out"
    folder.mkdir()
    values = {"a0": 1.0, "a{level}": 2.0, "b{x}": 3.0}
    for stem, value in values.items():
        _map(folder / f"{stem}.exr", value)
    run = envconv("batch", folder, "--out", out / "{stem}.exr", "resample", "--to", "latlong",
                  "--size", 8)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert sorted(os.listdir(out)) == sorted(f"{stem}.exr" for stem in values)
    from envconv import io

    for stem, value in values.items():
        assert np.allclose(io.read(out / f"{stem}.exr").pixels, value, rtol=1e-3), stem
    assert not litter(tmp_path)


def test_a_face_set_inputs_stem_names_its_set(tmp_path):
    """{stem} of sky_{face}.exr was "sky_{face}": 'out/{stem}_{face}.exr' wrote
    out/sky_px_px.exr. It is "sky", the set's name."""
    import envconv as library

    (tmp_path / "in").mkdir()
    faces = library.EnvMap(np.full((4, 24, 3), 0.5, np.float32), "cube-faces")
    library.write(faces, tmp_path / "in" / "sky_{face}.exr")
    run = envconv("batch", tmp_path / "in" / "sky_{face}.exr", "--out",
                  tmp_path / "out" / "{stem}_{face}.exr", "resample", "--to", "cube-faces",
                  "--size", 4)  # fmt: skip
    assert run.returncode == 0, run.stderr
    faces = ("px", "nx", "py", "ny", "pz", "nz")
    assert sorted(os.listdir(tmp_path / "out")) == sorted(f"sky_{f}.exr" for f in faces)


def test_two_inputs_on_one_set_of_level_files_are_refused_before_any_work(tmp_path):
    """{level} paths were left out of the duplicate check ("needs a header"): the second job
    replaced the first one's level files. The sizes are known, so are the final names."""
    for name in ("d1", "d2"):
        (tmp_path / name).mkdir()
        _map(tmp_path / name / "x.exr")
    out = tmp_path / "out"
    run = envconv("batch", tmp_path / "d1" / "x.exr", tmp_path / "d2" / "x.exr", "--out",
                  out / "{stem}_{level}.png", "resample", "--to", "latlong", "--size", 8,
                  "--mips", 2)  # fmt: skip
    _refused(run, tmp_path, message="would both write")
    assert not out.exists()


def test_face_in_a_folder_name_makes_one_folder_per_face(tmp_path):
    """'out/{face}/sky.exr' made a literal '{face}' folder, then failed on out/px."""
    source = _map(tmp_path / "sky.exr", 0.5)
    run = envconv("convert", source, tmp_path / "out" / "{face}" / "sky.exr", "--to",
                  "cube-faces", "--size", 4)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert sorted(os.listdir(tmp_path / "out")) == sorted(["px", "nx", "py", "ny", "pz", "nz"])
    from envconv import io

    back = io.read(str(tmp_path / "out" / "{face}" / "sky.exr"))
    assert back.layout.name == "cube-faces" and np.allclose(back.pixels, 0.5, rtol=1e-3)


def test_long_output_names_are_written(tmp_path):
    """Names of 215-255 bytes are legal, but their temps (36 bytes longer) were not: exit 3."""
    source = _map(tmp_path / "sky.exr")
    targets = [tmp_path / ("a" * (length - 4) + ".exr") for length in (215, 251, 255)]
    writes = [arg for target in targets for arg in ("write", target)]
    run = envconv("read", source, "resample", "--to", "latlong", "--size", 4, *writes)
    assert (run.returncode, run.stderr) == (0, ""), run.stderr
    assert sorted(os.listdir(tmp_path)) == sorted([*(t.name for t in targets), "sky.exr"])


def test_a_name_longer_than_the_file_system_allows_is_refused(tmp_path):
    source = _map(tmp_path / "sky.exr")
    run = envconv("convert", source, tmp_path / ("a" * 252 + ".exr"), "--to", "latlong",
                  "--size", 4)  # fmt: skip
    _refused(run, tmp_path, message="256 bytes long")


def test_an_output_that_is_a_folder_is_refused(tmp_path):
    source = _map(tmp_path / "sky.exr")
    (tmp_path / "out.exr").mkdir()
    run = envconv("convert", source, tmp_path / "out.exr", "--to", "latlong", "--size", 4)
    _refused(run, tmp_path, message="folder")
    assert os.listdir(tmp_path / "out.exr") == []


def _immutable(path) -> bool:
    """chattr +i ``path`` (root, on a file system with the flag); False where it cannot be."""
    import shutil

    chattr = shutil.which("chattr")
    if chattr is None:
        return False
    done = subprocess.run([chattr, "+i", str(path)], capture_output=True)
    return done.returncode == 0


def test_eperm_on_the_rename_is_one_line(tmp_path):
    source = _map(tmp_path / "sky.exr")
    (tmp_path / "out").mkdir()
    target = _map(tmp_path / "out" / "o.exr", 5.0)
    before = snapshot(target)
    if not _immutable(target):
        pytest.skip("chattr +i is not available here (needs root and a file system with it)")
    try:
        run = envconv("convert", source, target, "--to", "latlong", "--size", 8)
    finally:
        subprocess.run(["chattr", "-i", str(target)])
    assert_failed_cleanly(run, 1, tmp_path, message=f"cannot write {target}")
    assert_untouched(before)


def test_a_face_set_whose_one_file_cannot_be_replaced_stays_old(tmp_path):
    """Six renames, the fourth refused (EPERM): a mixed set was left. All six stay old."""
    out = tmp_path / "out"
    first = envconv("convert", _map(tmp_path / "a.exr", 1.0), out / "s_{face}.exr", "--to",
                    "cube-faces", "--size", 4)  # fmt: skip
    assert first.returncode == 0, first.stderr
    files = [out / f"s_{face}.exr" for face in ("px", "nx", "py", "ny", "pz", "nz")]
    before = snapshot(*files)
    if not _immutable(files[3]):
        pytest.skip("chattr +i is not available here (needs root and a file system with it)")
    try:
        run = envconv("convert", _map(tmp_path / "b.exr", 2.0), out / "s_{face}.exr", "--to",
                      "cube-faces", "--size", 4)  # fmt: skip
    finally:
        subprocess.run(["chattr", "-i", str(files[3])])
    assert_failed_cleanly(run, 1, tmp_path, message=f"cannot write {files[3]}")
    assert_untouched(before)
    assert sorted(os.listdir(out)) == sorted(f.name for f in files)


def test_a_stray_temp_with_a_huge_pid_is_cleaned(tmp_path):
    from envconv.io.temps import _host

    source = _map(tmp_path / "sky.exr")
    stray = tmp_path / f".x.envconv-{_host()}-{10**30}-0badf00d.tmp.exr"
    stray.write_bytes(b"partial")
    run = envconv("convert", source, tmp_path / "o.exr", "--to", "latlong", "--size", 4)
    assert (run.returncode, run.stderr) == (0, ""), run.stderr
    assert sorted(os.listdir(tmp_path)) == ["o.exr", "sky.exr"]


def test_a_live_runs_temp_is_kept_whatever_its_pid_says(tmp_path):
    """A run in another PID namespace (a container) names its temp with a PID that is dead
    here: its lock on the temp, not the PID, says it is alive. A stale temp (no lock) goes."""
    import fcntl

    from envconv.io.temps import _host

    source = _map(tmp_path / "sky.exr")
    live = tmp_path / f".x.envconv-{_host()}-{_dead_pid()}-00c0ffee.tmp.exr"
    stale = tmp_path / f".y.envconv-{_host()}-{_dead_pid()}-0badf00d.tmp.exr"
    stale.write_bytes(b"partial")
    with open(live, "wb") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        handle.write(b"being written")
        run = envconv("convert", source, tmp_path / "o.exr", "--to", "latlong", "--size", 4)
        assert (run.returncode, run.stderr) == (0, ""), run.stderr
        assert sorted(os.listdir(tmp_path)) == sorted([live.name, "o.exr", "sky.exr"])


def _deep_exr(path):
    import OpenImageIO as oiio

    spec = oiio.ImageSpec(4, 2, 2, oiio.FLOAT)
    spec.channelnames = ("R", "Z")
    spec.deep = True
    buf = oiio.ImageBuf(spec)
    for y in range(2):
        for x in range(4):
            buf.set_deep_samples(x, y, 0, (x + y) % 3)  # 0, 1 or 2 samples
            for s in range((x + y) % 3):
                buf.set_deep_value(x, y, 0, 0, s, 0.5 + s)
                buf.set_deep_value(x, y, 0, 1, s, 1.0 + s)
    assert buf.write(str(path)), buf.geterror()
    return path


def test_info_describes_a_deep_exr_and_convert_refuses_it(tmp_path):
    source = _deep_exr(tmp_path / "deep.exr")
    before = snapshot(source)
    info = envconv("info", source, "--json")
    assert info.returncode == 0 and info.stderr == "", info.stderr
    record = json.loads(info.stdout)
    assert record["deep"] is True and record["channels"] == ["R", "Z"]
    assert record["samples_per_pixel"] == [0, 2] and record["layout"] == "unknown"
    assert record["width"] == 4 and record["height"] == 2
    _convert_fails(tmp_path, source, 1, "deep")
    assert_untouched(before)


@pytest.mark.parametrize("started", [True, False])
def test_an_interrupted_kernel_start_lets_nothing_run_on(monkeypatch, started):
    """A signal that lands while the kernel's helper thread starts (Thread.start waits for it
    to begin, and the wait takes the signal) must not leave the kernel running behind the
    exception: the process would then finalise while the helper is inside the core, and its
    return would abort the process (SIGABRT, 'terminate called without an active exception';
    seen 1 to 3 times in 100 Ctrl-Cs 30-50 ms into a small conversion). Either the kernel
    never starts, or it has returned before the exception goes on. Here Thread.start raises
    KeyboardInterrupt once the helper has begun (``started``) or before it can."""
    import _thread
    import threading

    from envconv.resample import kernels

    events = []
    original = threading.Thread.start

    def interrupted_start(self):
        if started:
            original(self)
            time.sleep(0.05)  # the helper is inside the kernel now
        else:
            _thread.start_new_thread(original, (self,))  # begins after the raise
        raise KeyboardInterrupt

    def kernel(progress):
        events.append("began")
        time.sleep(0.3)
        events.append("returned")

    monkeypatch.setattr(threading.Thread, "start", interrupted_start)
    monkeypatch.setattr(kernels, "_watcher", lambda done, total: None)
    with pytest.raises(KeyboardInterrupt):
        kernels._run_watched(kernel, 1)
    expected = ["began", "returned"] if started else []
    assert events == expected, events  # returned before the exception went on, or never began
    time.sleep(0.4)  # a helper that began after the raise would have run by now
    assert events == expected, events
