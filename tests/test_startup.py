"""A one-shot command's start-up and end: lazy imports, cached-kernel loading, exit status.

These are the parts of ``envconv convert``'s wall time that come before and around the work
(see benchmarks/bench.py e2e for the figures). Each test checks what a user relies on: the
same pixels whichever way they were decoded or loaded, and no heavy import where none is used.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

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


def test_importing_the_command_line_loads_neither_numba_nor_the_layouts():
    """The entry point stays light until a command needs the kernels (``layouts --help`` or a
    usage error should not wait for them)."""
    out = _run_python(
        "import sys, envconv, envconv.cli, envconv.file_io\n"
        "print(sorted(m for m in ('numba', 'envconv.layouts', 'envconv.resample') if m in sys.modules))"
    )
    assert out.strip() == "[]"


def test_lazy_package_attributes_resolve_and_unknown_names_fail():
    assert envconv.read is envconv.io.read and envconv.convert is envconv.resample.convert
    assert envconv.EnvMap is envconv.envmap.EnvMap
    assert "convert" in dir(envconv)
    with pytest.raises(AttributeError):
        envconv.no_such_name  # noqa: B018


def test_a_fresh_process_loads_cached_kernels_without_numbas_compiler_registries(tmp_path):
    """numba's cache loader would import and install all of its typing and lowering registries
    (numba.np.linalg among them) first; envconv's dispatchers skip that. Nor may a kernel make
    arrays with np.empty or np.zeros (envconv.kernels.scratch instead), which would make loading
    it import numba.np.arrayobj (0.05 s), nor typing a
    plain ndarray argument import numpy.ma (numba's MaskedArray check, 0.013 s). The pixels a
    fresh process computes from the cache must equal this process's, bit for bit, for the main
    kernels: resampling (parallel), the rip-map and a mip chain."""
    import analytic
    import naive

    source = envconv.EnvMap(naive.pixel_average("latlong", 64, analytic.radiance, samples=2), "latlong")
    envconv.write(source, tmp_path / "src.exr", bit_depth="float")
    source = envconv.read(tmp_path / "src.exr")
    jobs = {"cross": dict(to="cube-vcross", size=32), "mips": dict(to="latlong", size=32, mips=True),
            "ball": dict(to="sphere", size=48, samples=3, filter="bicubic")}  # fmt: skip
    expected = {}
    for name, kwargs in jobs.items():  # also fills the cache for these signatures
        result = envconv.convert(source, **kwargs)
        expected[name] = result.levels if kwargs.get("mips") else [result.pixels]
    code = (
        "import sys, numpy as np, envconv\n"
        f"source = envconv.read({str(tmp_path / 'src.exr')!r})\n"
        f"for name, kwargs in {jobs!r}.items():\n"
        "    r = envconv.convert(source, **kwargs)\n"
        "    levels = r.levels if kwargs.get('mips') else [r.pixels]\n"
        f"    np.savez({str(tmp_path)!r} + '/' + name + '.npz', *levels)\n"
        "print([m for m in ('numba.np.linalg', 'numba.np.arrayobj', 'numpy.ma') if m in sys.modules])\n"
    )
    assert _run_python(code).strip() == "[]"
    for name, levels in expected.items():
        with np.load(tmp_path / f"{name}.npz") as saved:
            assert len(saved.files) == len(levels)
            for k, level in enumerate(levels):
                np.testing.assert_array_equal(saved[f"arr_{k}"], level, err_msg=name)


def test_a_function_loaded_from_the_cache_still_links_into_a_new_compilation():
    """A cached library's linking bitcode is parsed only when something links it. A fresh
    process loads a helper from the cache, calls it, then compiles a new function that calls
    it: both must give this process's value, and the helper must have come from the cache."""
    from envconv.kernels.geometry import FAMILY_CUBE_GL, density

    expected = density(FAMILY_CUBE_GL, 2, 0.25, -0.5)  # compiles (or loads) and caches it
    out = _run_python(
        "import numba\n"
        "from envconv.kernels.geometry import FAMILY_CUBE_GL, density\n"
        "loaded = density(FAMILY_CUBE_GL, 2, 0.25, -0.5)\n"
        "hits = sum(density._cache_hits.values())\n"
        "@numba.njit\n"
        "def twice(a, b):\n"
        "    return 2.0 * density(FAMILY_CUBE_GL, 2, a, b)\n"
        "print(repr(loaded), repr(twice(0.25, -0.5)), hits)\n"
    )
    loaded, linked, hits = out.split()
    assert float(loaded) == expected and float(linked) == 2.0 * expected
    assert int(hits) == 1


def test_envconv_dispatchers_type_plain_arrays_as_numba_does():
    """The typing that skips numba's MaskedArray check must give numba's own answer for every
    layout, dtype, dimension and write flag, and leave anything else to numba."""
    from numba.core.typing.typeof import Purpose, typeof

    from envconv.kernels.ripmap import _fill_rips

    base = np.arange(2 * 3 * 4 * 5, dtype=np.float64).reshape(2, 3, 4, 5)
    readonly = np.ones((3, 4), np.float32)
    readonly.flags.writeable = False
    values = [base, base[:, ::2], np.asfortranarray(base), base[..., 0], base.astype(np.float32),
              base.astype(np.int64), base > 3, np.float32(2.0).reshape(()), readonly,
              np.empty((0, 3), np.uint16), np.zeros(5, np.complex64), 3, 2.5, (1, 2.0)]  # fmt: skip
    for value in values:
        assert _fill_rips.typeof_pyval(value) == typeof(value, Purpose.argument), repr(value)
    masked = np.ma.masked_array(np.zeros(3))  # numba refuses it, and so must envconv
    with pytest.raises(Exception, match="MaskedArray"):
        _fill_rips.typeof_pyval(masked)


def test_numbas_runtime_functions_load_from_envconvs_cache_and_a_bad_file_is_replaced(tmp_path):
    """NRT's LLVM functions are compiled once and their machine code kept beside the kernels'
    cache. A fresh process must load them (compiling is made to fail) and give the same pixels;
    a damaged file must be compiled again and rewritten, never break a conversion."""
    import pickle

    from envconv.kernels.resample import resample_rows

    source = envconv.EnvMap(np.random.default_rng(3).uniform(0, 9, (32, 64, 3)).astype(np.float32), "latlong")
    envconv.write(source, tmp_path / "src.exr", bit_depth="float")
    expected = envconv.convert(envconv.read(tmp_path / "src.exr"), "cube-vcross", size=16).pixels
    convert = (
        "import numpy as np, envconv\n"
        f"r = envconv.convert(envconv.read({str(tmp_path / 'src.exr')!r}), 'cube-vcross', size=16)\n"
        f"np.save({str(tmp_path / 'out.npy')!r}, r.pixels)\n"
    )
    cache_dir = resample_rows._cache._cache_path
    saved = sorted(f for f in os.listdir(cache_dir) if f.startswith("nrt-") and f.endswith(".nbo"))
    assert saved, "the first kernel load of this process should have saved NRT's machine code"
    for name in saved:
        (Path(cache_dir) / name).write_bytes(b"damaged")
    _run_python(convert)
    np.testing.assert_array_equal(np.load(tmp_path / "out.npy"), expected)
    for name in saved:
        assert pickle.loads((Path(cache_dir) / name).read_bytes())[1] == "object"
    no_compiling = (
        "from numba.core.runtime import nrtdynmod\n"
        "def refuse(*args):\n"
        "    raise AssertionError('NRT compiled although its machine code was cached')\n"
        "nrtdynmod.compile_nrt_functions = nrtdynmod.create_nrt_module = refuse\n"
    )
    _run_python(no_compiling + convert)
    np.testing.assert_array_equal(np.load(tmp_path / "out.npy"), expected)
    assert not [f for f in os.listdir(cache_dir) if f.endswith(".tmp")]


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


def test_installed_versions_are_what_importlib_metadata_says():
    """envconv._cached_kernels reads numba's version from its dist-info directory, without
    importing importlib.metadata (0.02 s of a one-shot command)."""
    from importlib import metadata

    from envconv._versions import installed_version

    for name in ("numba", "OpenImageIO", "opencolorio", "llvmlite", "numpy", "click", "OpenEXR"):
        assert installed_version(name) == metadata.version(name), name
    assert installed_version("no-such-distribution-here") is None
