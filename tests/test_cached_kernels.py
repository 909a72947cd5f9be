"""Cached kernels run without numba (envconv._cached_kernels, envconv._jit's deferral).

A process the command line runs loads numba's cached machine code with llvmlite and never
imports numba, unless something needs numba itself: then numba is imported and takes over.
The truth here is numba's own: its ``typeof`` names, the results its dispatchers give in this
process, and its thread pool.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numba
import numpy as np
import pytest

import envconv
from envconv import _cached_kernels

#: The environment of a command-line process that may defer numba (no numba settings).
CLEAN_ENV = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_") and k != "ENVCONV_IMPORT_NUMBA"}

pytestmark = pytest.mark.skipif(
    sys.platform != "linux" or not numba.__version__.startswith(_cached_kernels.NUMBA_VERSIONS_KNOWN),
    reason="the loader serves known numba versions on Linux only",
)

_KERNELS = '''
from envconv._jit import jit, jit_parallel, prange


@jit_parallel
def ramp(out, scale, offset):
    for i in prange(out.shape[0]):
        out[i] = scale * i + offset


@jit
def weighted(values, weight):
    total = 0.0
    for v in values:
        total += v * weight
    return total


@jit
def doubled(values):
    return values * 2.0


@jit
def checked(value):
    if value < 0.0:
        raise ValueError("negative value")
    return value * 2.0
'''


def _run(code: str, *args: str, cwd=None, env=None) -> list[str]:
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code), *args], cwd=cwd,
                          env=CLEAN_ENV if env is None else env, capture_output=True, text=True)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


@pytest.fixture
def kernel_module(tmp_path, monkeypatch):
    """A module of three small kernels in ``tmp_path``, compiled and cached by numba here."""
    (tmp_path / "tiny_kernels.py").write_text(_KERNELS)
    monkeypatch.syspath_prepend(str(tmp_path))
    sys.modules.pop("tiny_kernels", None)
    import tiny_kernels

    out = np.zeros(1000)
    tiny_kernels.ramp(out, 0.5, 2.0)
    tiny_kernels.weighted(np.arange(5.0), 3.0)
    tiny_kernels.doubled(np.arange(3.0))
    tiny_kernels.checked(1.0)
    yield tmp_path
    sys.modules.pop("tiny_kernels", None)


_PROBE = """
import sys
import numpy as np
import envconv
envconv._COMMAND_LINE_PROCESS = True
sys.path.insert(0, sys.argv[1])
import tiny_kernels
from envconv import _cached_kernels
out = np.zeros(1000)
tiny_kernels.ramp(out, 0.5, 2.0)
print(bool(np.array_equal(out, 0.5 * np.arange(1000) + 2.0)))
print(tiny_kernels.weighted(np.arange(5.0), 3.0))
print('numba' in sys.modules, _cached_kernels.threading_layer())
"""


def test_cached_kernels_run_without_numba_and_give_numbas_results(kernel_module):
    """A parallel kernel and a kernel returning a number, cached by numba in this process, run
    in a command-line process without importing numba, on numba's own threading layer."""
    here_out = np.zeros(1000)
    import tiny_kernels

    tiny_kernels.ramp(here_out, 0.5, 2.0)
    expected_sum = tiny_kernels.weighted(np.arange(5.0), 3.0)
    ok, total, numba_loaded, layer = _run(_PROBE, str(kernel_module))
    assert ok == "True"
    assert float(total) == expected_sum == 30.0
    assert numba_loaded == "False"
    assert layer == numba.threading_layer()


def test_a_changed_source_file_is_numbas_business(kernel_module):
    """numba's cache entry is keyed by the source file's hash: once the file changes, the
    kernel is not loaded from the stale entry but compiled by numba, and is still right."""
    path = kernel_module / "tiny_kernels.py"
    path.write_text(path.read_text().replace("out[i] = scale * i + offset", "out[i] = scale * i + offset + 1.0"))
    code = _PROBE.replace("2.0)))", "3.0)))")
    ok, _total, numba_loaded, _layer = _run(code, str(kernel_module))
    assert ok == "True" and numba_loaded == "True"


def test_a_kernel_raising_an_exception_raises_it_without_numba(kernel_module):
    """numba's wrapper turns a kernel's ``raise`` into the Python exception, as numba would."""
    code = """
    import sys
    import envconv
    envconv._COMMAND_LINE_PROCESS = True
    sys.path.insert(0, sys.argv[1])
    import tiny_kernels
    print(tiny_kernels.checked(2.5), 'numba' in sys.modules)
    try:
        tiny_kernels.checked(-1.0)
    except ValueError as exc:
        print(type(exc).__name__, str(exc).replace(' ', '_'))
    print(tiny_kernels.checked(1.5))
    """
    assert _run(code, str(kernel_module)) == ["5.0", "False", "ValueError", "negative_value", "3.0"]


def test_numba_takes_over_when_a_kernel_needs_it(kernel_module):
    """Arguments of a type no cache entry has, and a kernel returning an array (whose boxing
    numba rebuilds), import numba; every deferred kernel then becomes numba's dispatcher, and
    numba adopts the thread pool already running (one pool, numba's thread count)."""
    code = """
    import sys
    import numpy as np
    import envconv
    envconv._COMMAND_LINE_PROCESS = True
    sys.path.insert(0, sys.argv[1])
    import tiny_kernels
    from envconv import _jit
    out = np.zeros(100)
    tiny_kernels.ramp(out, 0.5, 2.0)
    print('numba' in sys.modules)
    print(tiny_kernels.ramp._cached_call((np.zeros(4, np.float32), 1.0, 0.0)) is None)
    print(tiny_kernels.ramp._cached_call((np.zeros((4, 2))[:, 0], 1.0, 0.0)) is None)
    print(tiny_kernels.ramp._cached_call((np.zeros(4), 1, 0.0)) is None)
    print('numba' in sys.modules)
    print(tiny_kernels.doubled(np.arange(3.0)).tolist())
    import numba
    print(isinstance(tiny_kernels.ramp, _jit._Deferred), isinstance(_jit.prange, _jit._Placeholder))
    f32 = np.zeros(100, np.float32)
    tiny_kernels.ramp(f32, 0.5, 2.0)
    print(bool(np.array_equal(f32, 0.5 * np.arange(100, dtype=np.float32) + 2)))
    print(numba.threading_layer(), numba.get_num_threads(), numba.config.NUMBA_NUM_THREADS)
    """
    lines = _run(code, str(kernel_module))
    assert lines[:5] == ["False", "True", "True", "True", "False"]
    assert " ".join(lines[5:8]) == "[0.0, 2.0, 4.0]"
    assert lines[8:11] == ["False", "False", "True"]
    assert lines[11] == numba.threading_layer()
    assert lines[12] == lines[13] == str(numba.config.NUMBA_NUM_THREADS)


@pytest.mark.parametrize(
    "setting", ["ENVCONV_IMPORT_NUMBA=1", "NUMBA_NUM_THREADS=1", "version 0.99.0", "library"]
)
def test_numba_is_imported_as_usual_where_the_loader_is_not_sure(kernel_module, setting):
    """numba's settings (environment variables), an unknown numba version, a library import in
    someone else's program, or ENVCONV_IMPORT_NUMBA=1: numba is imported and does the work."""
    env = dict(CLEAN_ENV)
    code = _PROBE
    if "=" in setting:
        name, value = setting.split("=")
        env[name] = value
    elif setting == "library":
        code = code.replace("envconv._COMMAND_LINE_PROCESS = True", "")
    else:
        code = code.replace(
            "import tiny_kernels\n",
            "from envconv import _cached_kernels\n_cached_kernels._numba_version = lambda: '0.99.0'\nimport tiny_kernels\n",
        )
    ok, total, numba_loaded, layer = _run(code, str(kernel_module), env=env)
    assert ok == "True" and float(total) == 30.0
    assert numba_loaded == "True" and layer == "None"


def test_argument_type_names_are_numbas():
    """What arg_type_name gives is what numba.typeof says; anything else is left to numba."""
    base = np.arange(24.0).reshape(2, 3, 4)
    readonly = np.arange(3, dtype=np.int32)
    readonly.flags.writeable = False
    values = [
        base, base.astype(np.float32), base[:, :, ::2], np.asfortranarray(base[0]), base[0, 0],
        np.zeros(3, np.bool_), np.zeros(3, np.uint8), np.zeros(2, np.complex64), readonly,
        np.zeros((0, 3), np.int64), True, 7, -(2**63), 2.5, np.float32(1.5), np.int32(4), np.bool_(True),
    ]  # fmt: skip
    for value in values:
        assert _cached_kernels.arg_type_name(value) == str(numba.typeof(value)), value
    unaligned = np.frombuffer(b"\0" * 33, np.float64, count=4, offset=1)
    for value in [2**63, "s", (1, 2), [1.0], None, np.zeros(2, ">f8"), unaligned, np.zeros(2, "U3"),
                  np.ma.masked_array([1.0])]:  # fmt: skip
        assert _cached_kernels.arg_type_name(value) is None, value


def test_elf_symbols_of_a_cached_kernel(kernel_module):
    """The symbol reader that guards LLVM's linker finds the kernel's own wrapper among the
    object's definitions and the thread pool's entry among its needs; non-ELF data is refused."""
    import tiny_kernels

    (signature,) = tiny_kernels.ramp.signatures
    library = tiny_kernels.ramp.overloads[signature].library
    object_code = library.serialize_using_object_code()[2][0]
    defined, undefined = _cached_kernels._elf_symbols(object_code)
    mangled = tiny_kernels.ramp.overloads[signature].fndesc.mangled_name
    assert "_ZN7cpython" + mangled[3:] in defined and mangled in defined
    assert "numba_parallel_for" in undefined and not undefined & defined
    assert _cached_kernels._elf_symbols(b"not an object file") is None


def test_the_command_line_converts_without_numba(tmp_path):
    """The real thing: ``envconv convert`` and its kernels (resampling, rip-maps, densities,
    alpha, guard rings, mips) in a fresh process, without numba, write what the same command
    run in this process (by numba) writes."""
    from conftest import run_cli

    rng = np.random.default_rng(4)
    source = envconv.EnvMap(rng.uniform(0, 50, (64, 128, 3)).astype(np.float32), "latlong")
    envconv.write(source, tmp_path / "src.exr", bit_depth="float")
    cases = [
        ["--to", "cube-vcross", "--size", "16"],
        ["--to", "sphere", "--size", "24", "--filter", "bicubic", "--alpha", "--rotate", "30,10,5"],
        ["--to", "cube-hcross", "--size", "16", "--guard", "2", "--alpha", "--mips"],
        ["--to", "paraboloid", "--size", "12", "--guard", "fill", "--samples", "3", "--filter", "nearest"],
    ]
    code = """
    import atexit, sys
    from envconv.cli.main import main
    atexit.register(lambda: print('numba' in sys.modules))
    sys.argv = ['envconv', *sys.argv[1:]]
    main()
    """
    for number, options in enumerate(cases):
        expected, written = tmp_path / f"here{number}.exr", tmp_path / f"cli{number}.exr"
        assert run_cli(["convert", tmp_path / "src.exr", expected, *options]).exit_code == 0  # caches
        lines = _run(code, "convert", str(tmp_path / "src.exr"), str(written), *options)
        assert lines[-1] == "False", options
        np.testing.assert_array_equal(envconv.read(written).pixels, envconv.read(expected).pixels)
        if "--mips" in options:  # the lower levels too, as stored
            import OpenImageIO as oiio

            for level in range(1, 4):
                buffers = [oiio.ImageBuf(str(path), 0, level) for path in (written, expected)]
                pixels = [b.get_pixels(oiio.FLOAT) for b in buffers]
                assert not any(b.has_error for b in buffers) and pixels[0].size > 0
                np.testing.assert_array_equal(*pixels)


def test_preloading_finds_the_conversion_kernels_without_numba():
    """``preload_kernels`` (called before a one-shot convert reads its input) loads the
    cached kernels a conversion runs, so that their first call finds them ready."""
    source = envconv.EnvMap(np.ones((16, 32, 3), np.float32), "latlong")
    envconv.convert(source, to="cube-vcross", size=8)  # cached here first
    code = """
    import sys
    import envconv
    envconv._COMMAND_LINE_PROCESS = True
    from envconv.resample import preload_kernels
    from envconv.kernels import mapping, resample, ripmap
    preload_kernels()
    kernels = (resample.resample_rows, ripmap._fill_rips, mapping.dir_density)
    print(all(len(k._overloads) >= 1 for k in kernels), 'numba' in sys.modules)
    """
    assert _run(code) == ["True", "False"]


def test_the_c_math_names_are_numbas():
    """The math functions bound by name, as numba binds them (its INTR_MATH)."""
    from numba.core.intrinsics import INTR_MATH

    assert set(_cached_kernels._C_MATH) == set(INTR_MATH)
