"""A one-shot command's start-up and end: lazy imports and the exit status.

These are the parts of ``envconv convert``'s wall time that come before and around the work
(see benchmarks/bench.py targets for the figures): no heavy import where none is used, and an
ending like any Python program's.
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from conftest import write_plain

import envconv

ENVCONV = os.path.join(os.path.dirname(sys.executable), "envconv")


def _image(path, seed, shape=(16, 32, 3)):
    pixels = np.random.default_rng(seed).uniform(0, 50, shape).astype(np.float32)
    write_plain(path, pixels)
    return pixels


def _run_python(code: str) -> str:
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_importing_the_command_line_loads_neither_the_core_nor_the_layouts():
    """The entry point stays light until a command needs the kernels (``layouts --help`` or a
    usage error should not wait for them); nothing imports numba any more."""
    out = _run_python(
        "import sys, envconv, envconv.cli, envconv.io.files\n"
        "print(sorted(m for m in ('numba', 'envconv._core', 'envconv.layouts', 'envconv.resample.convert')"
        " if m in sys.modules))"
    )
    assert out.strip() == "[]"


def test_lazy_package_attributes_resolve_and_unknown_names_fail():
    assert envconv.read is envconv.io.read and envconv.convert is envconv.resample.convert.convert
    assert envconv.EnvMap is envconv.envmap.EnvMap
    assert "convert" in dir(envconv)
    with pytest.raises(AttributeError):
        envconv.no_such_name  # noqa: B018


def test_the_console_script_ends_with_the_status_and_output_of_the_command(tmp_path):
    """The console script ends as any Python program does: status 0 with the paths written on
    stdout, 1 and one line on stderr for bad input, 2 for bad usage, atexit handlers run."""
    source = tmp_path / "in.exr"
    _image(source, 3)
    ok = subprocess.run([ENVCONV, "convert", str(source), str(tmp_path / "out.exr"), "--to",
                         "cube-vcross", "--size", "8", "--from", "latlong"],
                        capture_output=True, text=True)  # fmt: skip
    assert ok.returncode == 0, ok.stderr
    assert ok.stdout.strip() == str(tmp_path / "out.exr") and (tmp_path / "out.exr").is_file()
    bad = subprocess.run([ENVCONV, "convert", str(tmp_path / "missing.exr"), str(tmp_path / "o.exr"),
                          "--to", "latlong"], capture_output=True, text=True)  # fmt: skip
    assert bad.returncode == 1 and len(bad.stderr.strip().splitlines()) == 1
    usage = subprocess.run([ENVCONV, "convert", str(source)], capture_output=True, text=True)
    assert usage.returncode == 2
    code = (
        "import atexit, sys\n"
        "atexit.register(lambda: print('atexit ran', flush=False))\n"
        "sys.argv = ['envconv', 'layouts']\n"
        "from envconv.cli import main\n"
        "main()\n"
    )
    handlers = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert handlers.returncode == 0
    assert handlers.stdout.splitlines()[0].startswith("latlong")
    assert handlers.stdout.splitlines()[-1] == "atexit ran"


_BLAS_PROBE = (
    "import os, sys\n"
    "sys.argv = ['envconv', '--version']\n"
    "from envconv.cli import main\n"
    "try:\n"
    "    main()\n"
    "except SystemExit:\n"
    "    pass\n"
    "import numpy\n"
    "print(os.environ.get('OPENBLAS_NUM_THREADS'), len(os.listdir('/proc/self/task')))\n"
)


@pytest.mark.skipif(
    not os.path.isdir("/proc/self/task") or len(os.sched_getaffinity(0)) < 2,
    reason="counts the process's threads in /proc on a machine of 2+ cores",
)
def test_the_command_line_starts_numpy_without_a_blas_thread_pool():
    """``envconv`` asks OpenBLAS for no thread pool before numpy loads (a one shot ends sooner
    and no idle BLAS thread competes with the core's); a value the user set is kept, and then
    OpenBLAS starts its pool as usual."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    ours = subprocess.run([sys.executable, "-c", _BLAS_PROBE], capture_output=True, text=True,
                          env=env, check=True).stdout.splitlines()[-1].split()  # fmt: skip
    theirs = subprocess.run([sys.executable, "-c", _BLAS_PROBE], capture_output=True, text=True,
                            env={**env, "OPENBLAS_NUM_THREADS": "2"},
                            check=True).stdout.splitlines()[-1].split()  # fmt: skip
    assert ours[0] == "1" and theirs[0] == "2"
    assert int(ours[1]) < int(theirs[1])
