"""Run envconv's cached kernels without importing numba: the command line's fast start.

numba compiles each kernel once and caches its machine code (``__pycache__/*.nbi`` and
``*.nbc``). A later process that only *runs* cached kernels still pays 0.15–0.2 s to import
numba, nearly all of it building a compiler it never uses. This module loads that same
machine code with llvmlite, which numba itself uses to load it, and numba's four small C
extensions (its runtime, helpers, function environments and thread pool), without importing
the numba package: 0.01–0.02 s.

What is loaded is exactly what numba would load: the cache entry numba's own lookup would pick
(same numba version, source-file hash, bytecode hash, argument types and host CPU), the same
object code, the same runtime functions and symbols, the same threading layer and thread
count. A call goes through numba's own compiled wrapper (``cpython.<kernel>``), which unboxes
the arguments as numba's dispatcher would. Anything this module is not sure of returns
``None`` so that the caller falls back on numba: another numba version, a ``NUMBA_*``
environment variable or ``.numba_config.yaml``, a cache entry missing or stale, argument types
with no exact cached signature, a kernel that returns anything but ``None`` or a number, an
object file whose external symbols cannot all be resolved, a platform that is not ELF.

Everything here is private to envconv and used only by :mod:`envconv._jit` in a process the
command line runs; numba's internals read here are those of the versions in
``NUMBA_VERSIONS_KNOWN``, checked by ``tests/test_cached_kernels.py``.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import importlib.machinery
import importlib.util
import io
import os
import pickle
import struct
import sys
import threading
from typing import Any, NamedTuple

#: numba versions whose cache format, symbol names and thread-pool start this module follows.
NUMBA_VERSIONS_KNOWN = ("0.68.",)

#: numba's extension modules loaded here, by their numba names, and the prefix numba gives the
#: symbols of their ``c_helpers`` (NRT's names that start with "_" keep their own).
_EXTENSIONS = {
    "numba._helperlib": "numba_",
    "numba._dynfunc": "numba_",
    "numba.core.runtime._nrt_python": "NRT_",
}

#: The C math functions numba binds, by their own names, to the addresses its helper library
#: holds (numba.core.intrinsics.INTR_MATH, installed by numba.core.externals).
_C_MATH = """
acos acosf acosh acoshf asin asinf asinh asinhf atan atan2 atan2f atanf atanh atanhf ceil ceilf
cos cosf cosh coshf exp expf expm1 expm1f fabs fabsf floor floorf fmod fmodf log log10 log10f
log1p log1pf logf pow powf round roundf sin sinf sinh sinhf sqrt sqrtf tan tanf tanh tanhf
trunc truncf
""".split()

#: Return types whose boxing needs nothing but the wrapper itself.
_SCALAR_RETURNS = {"none", "bool", "int64", "int32", "float64", "float32"}

#: numpy dtypes numba types by their numpy names.
_ARRAY_DTYPES = {
    "bool", "int8", "int16", "int32", "int64", "uint8", "uint16", "uint32", "uint64",
    "float32", "float64", "complex64", "complex128",
}  # fmt: skip

#: Where envconv's own kernels, and usually the runtime's machine code, are cached.
_ENVCONV_KERNEL_CACHE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "kernels", "__pycache__")

_lock = threading.RLock()
_runtime: _Runtime | None = None
_unavailable: str | None = None  # why the runtime could not start, once known


class Overload(NamedTuple):
    """One cached specialisation: numba's names of its argument types and the call."""

    arg_types: tuple[str, ...]
    call: Any  # (args tuple) -> result


# --------------------------------------------------------------------------------------------
# Reading numba's cache files without numba's classes


class _Recorded:
    """Stand-in for a numba class while unpickling: keeps the constructor arguments and state."""

    where: tuple[str, str] = ("", "")

    def __new__(cls, *args, **kwargs):
        self = object.__new__(cls)
        self.args, self.state = args, None
        return self

    def __init__(self, *args, **kwargs):
        self.args = args

    def __setstate__(self, state):
        self.state = state


class _StandInUnpickler(pickle.Unpickler):
    """Unpickles numba's cache files with stand-ins for numba's and llvmlite's classes."""

    _classes: dict[tuple[str, str], type] = {}

    def find_class(self, module, name):
        if module == "numba" or module.startswith(("numba.", "llvmlite")):
            key = (module, name)
            if key not in self._classes:
                self._classes[key] = type(name, (_Recorded,), {"where": key})
            return self._classes[key]
        return super().find_class(module, name)


def _unpickle(data: bytes):
    return _StandInUnpickler(io.BytesIO(data)).load()


def _type_state(recorded) -> dict:
    """The attribute dict of a pickled numba type (``_type_reconstructor(..., state)``)."""
    if isinstance(recorded, _Recorded) and len(recorded.args) == 3 and isinstance(recorded.args[2], dict):
        return recorded.args[2]
    raise ValueError("not a pickled numba type")


def _type_name(recorded) -> str:
    return _type_state(recorded)["name"]


# --------------------------------------------------------------------------------------------
# Argument types, as numba's typeof names them


def arg_type_name(value) -> str | None:
    """numba's name for the type it gives ``value`` (``array(float32, 3d, C)``, ``int64``...),
    or None for a value this module leaves to numba."""
    import numpy as np

    kind = type(value)
    if kind is np.ndarray:
        dtype = value.dtype
        if dtype.name not in _ARRAY_DTYPES or not dtype.isnative or not value.flags.aligned:
            return None
        flags = value.flags
        layout = "C" if flags.c_contiguous else "F" if flags.f_contiguous else "A"
        name = f"array({dtype.name}, {value.ndim}d, {layout})"
        return name if flags.writeable else f"readonly {name}"
    if kind is bool:
        return "bool"
    if kind is int:
        return "int64" if -(2**63) <= value < 2**63 else None
    if kind is float:
        return "float64"
    if isinstance(value, np.generic) and value.dtype.name in _ARRAY_DTYPES:
        return value.dtype.name
    return None


# --------------------------------------------------------------------------------------------
# ELF symbols: every external symbol of an object file must resolve before LLVM links it (an
# unresolved one aborts the process).


def _elf_symbols(data: bytes) -> tuple[set[str], set[str]] | None:
    """(defined global symbols, undefined symbols) of a 64-bit little-endian ELF relocatable
    object, or None for anything else."""
    if data[:4] != b"\x7fELF" or data[4] != 2 or data[5] != 1:
        return None
    (shoff,) = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum = struct.unpack_from("<HH", data, 0x3A)
    sections = [struct.unpack_from("<IIQQQQIIQQ", data, shoff + i * shentsize) for i in range(shnum)]
    defined, undefined = set(), set()
    for _name, kind, _flags, _addr, offset, size, link, _info, _align, entsize in sections:
        if kind != 2 or entsize != 24:  # SHT_SYMTAB
            continue
        strings = sections[link]
        str_offset, str_size = strings[4], strings[5]
        table = data[str_offset : str_offset + str_size]
        for start in range(offset + entsize, offset + size, entsize):  # entry 0 is null
            name_at, info, _other, section = struct.unpack_from("<IBBH", data, start)
            name = table[name_at : table.index(b"\0", name_at)].decode()
            if not name:
                continue
            bind = info >> 4
            if section == 0:
                undefined.add(name)
            elif bind in (1, 2):  # GLOBAL, WEAK
                defined.add(name)
    return defined, undefined


# --------------------------------------------------------------------------------------------
# The runtime: llvmlite's JIT engine, numba's C extensions and thread pool


def _numba_dir() -> str | None:
    spec = importlib.util.find_spec("numba")
    if spec is None or not spec.submodule_search_locations:
        return None
    return list(spec.submodule_search_locations)[0]


def _numba_version() -> str | None:
    from ._versions import installed_version

    return installed_version("numba")


def unavailable_reason() -> str | None:
    """Why cached kernels cannot run without numba in this process, or None when they can.

    Checked without loading anything: the numba version, the platform, numba's configuration
    (environment variables, ``.numba_config.yaml``)."""
    if "numba" in sys.modules:
        return "numba is already imported"
    if sys.platform != "linux":
        return f"platform {sys.platform}"
    version = _numba_version()
    if version is None or not version.startswith(NUMBA_VERSIONS_KNOWN):
        return f"numba {version} is not a version this loader knows"
    if any(name.startswith("NUMBA_") for name in os.environ):
        return "a NUMBA_* environment variable is set"
    if os.path.isfile(".numba_config.yaml"):
        return ".numba_config.yaml in the working directory"
    return None


def _load_extension(name: str, directory: str):
    """Import numba's extension module ``name`` from its file, without its parent packages.

    It is registered under its own name, so that a later ``import numba`` uses the very same
    module (one runtime, one thread pool)."""
    if name in sys.modules:
        return sys.modules[name]
    *packages, stem = name.split(".")[1:]
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        path = os.path.join(directory, *packages, stem + suffix)
        if os.path.isfile(path):
            break
    else:
        raise ImportError(f"no extension file for {name}")
    loader = importlib.machinery.ExtensionFileLoader(name, path)
    spec = importlib.util.spec_from_file_location(name, path, loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    sys.modules[name] = module
    return module


class _Runtime:
    """llvmlite's MCJIT engine with numba's runtime symbols, configured as numba configures its
    own (numba.core.codegen.JITCPUCodegen, numba.core.base._load_global_helpers,
    numba.core.runtime.nrt, numba.np.ufunc.parallel._launch_threads)."""

    def __init__(self, numba_dir: str, version: str):
        import llvmlite.binding as ll

        self.ll = ll
        self.version = version
        ll.initialize_native_target()
        ll.initialize_native_asmprinter()
        self.triple = ll.get_process_triple()
        self.cpu = ll.get_host_cpu_name()
        self.features = ll.get_host_cpu_features().flatten()
        self.magic = (self.triple, self.cpu, self.features)
        machine = ll.Target.from_triple(self.triple).create_target_machine(
            cpu=self.cpu, features=self.features, opt=3, reloc="static", codemodel="jitdefault", jit=True
        )
        module = ll.parse_assembly("")
        module.triple = self.triple
        self.engine = ll.create_mcjit_compiler(module, machine)
        self.defined: set[str] = set()
        self.keep_alive: list[Any] = []
        self.environments: dict[str, Any] = {}
        self.modules = {name: _load_extension(name, numba_dir) for name in _EXTENSIONS}
        ll.add_symbol("_Py_NoneStruct", id(None))
        for name, prefix in _EXTENSIONS.items():
            for py_name, address in self.modules[name].c_helpers.items():
                if prefix == "NRT_" and py_name.startswith("_"):
                    ll.add_symbol(py_name, address)  # NRT's internal API keeps its name
                else:
                    ll.add_symbol(prefix + py_name, address)
        helpers = self.modules["numba._helperlib"].c_helpers
        for name in _C_MATH:
            if name in helpers:
                ll.add_symbol(name, helpers[name])
        import builtins

        for value in vars(builtins).values():
            if isinstance(value, type) and issubclass(value, BaseException):
                ll.add_symbol(f"PyExc_{value.__name__}", id(value))
        self.threading_layer: str | None = None
        self.numba_dir = numba_dir
        self.nrt_loaded = False

    def launch_threads(self) -> None:
        """Start numba's thread pool as ``numba.np.ufunc.parallel._launch_threads`` does with the
        default settings: the first of TBB (a compatible libtbb), OpenMP and workqueue that loads,
        with one thread per CPU this process may run on."""
        if self.threading_layer is not None:
            return
        ll = self.ll
        library = name = None
        for candidate in ("tbb", "omp", "workqueue"):
            try:
                if candidate == "tbb":
                    libtbb = ctypes.CDLL("libtbb.so.12")
                    libtbb.TBB_runtime_interface_version.restype = ctypes.c_int
                    if libtbb.TBB_runtime_interface_version() < 12060:
                        continue
                module = "workqueue" if candidate == "workqueue" else f"{candidate}pool"
                library = _load_extension(f"numba.np.ufunc.{module}", self.numba_dir)
                name = candidate
                break
            except (ImportError, OSError, AttributeError):
                continue
        if library is None:
            raise ImportError("no numba threading layer loads")
        for symbol, attribute in (
            ("numba_parallel_for", "parallel_for"),
            ("do_scheduling_signed", "do_scheduling_signed"),
            ("do_scheduling_unsigned", "do_scheduling_unsigned"),
            ("allocate_sched", "allocate_sched"),
            ("deallocate_sched", "deallocate_sched"),
        ):
            ll.add_symbol(symbol, getattr(library, attribute))
        threads = max(1, len(os.sched_getaffinity(0)))
        ctypes.CFUNCTYPE(None, ctypes.c_int)(library.launch_threads)(threads)
        for symbol in ("get_num_threads", "set_num_threads", "get_thread_id", "set_parallel_chunksize",
                       "get_parallel_chunksize", "get_sched_size"):  # fmt: skip
            ll.add_symbol(symbol, getattr(library, symbol))
        ctypes.CFUNCTYPE(None, ctypes.c_int)(library.set_num_threads)(threads)
        self.threading_layer, self.thread_library, self.threads = name, library, threads

    def unresolved(self, names: set[str]) -> set[str]:
        address_of = self.ll.address_of_symbol
        return {name for name in names if name not in self.defined and not address_of(name)}

    def add_object(self, object_code: bytes, runtime_dirs: tuple[str, ...]) -> bool:
        """Add ELF object code to the engine once every symbol it needs resolves, loading the
        runtime's LLVM functions first if it calls them."""
        symbols = _elf_symbols(object_code)
        if symbols is None:
            return False
        defined, undefined = symbols
        missing = self.unresolved(undefined - defined)
        if missing and not self.nrt_loaded and any(self.load_nrt(d) for d in runtime_dirs):
            missing = self.unresolved(missing)
        if missing:
            return False
        self._add(object_code, defined)
        return True

    def _add(self, object_code: bytes, defined: set[str]) -> None:
        self.engine.add_object_file(self.ll.ObjectFileRef.from_data(object_code))
        self.engine.finalize_object()
        self.defined |= defined

    def load_nrt(self, cache_dir: str) -> bool:
        """Load the runtime's LLVM functions (reference counts and the like), whose machine code
        :func:`envconv._jit._start_runtime` keeps in a kernel cache directory."""
        key = repr((self.version, self.magic)).encode()
        path = os.path.join(cache_dir, f"nrt-{hashlib.sha256(key).hexdigest()[:16]}.nbo")
        try:
            with open(path, "rb") as f:
                _name, kind, (object_code, _bitcode) = pickle.load(f)
        except Exception:  # absent or unreadable: numba compiles them
            return False
        symbols = _elf_symbols(object_code) if kind == "object" else None
        if symbols is None or self.unresolved(symbols[1] - symbols[0]):
            return False
        self._add(object_code, symbols[0])
        self.nrt_loaded = True
        return True

    def environment(self, module_name: str, env_name: str):
        """numba's environment object for a function of ``module_name`` (its globals)."""
        env = self.environments.get(env_name)
        if env is None:
            module = sys.modules.get(module_name)
            namespace = vars(module) if module is not None else {"__name__": module_name}
            env = self.modules["numba._dynfunc"].Environment(namespace)
            self.environments[env_name] = env
        address = self.engine.get_global_value_address(env_name)
        if address:
            ctypes.c_void_p.from_address(address).value = id(env)
        return env


def _get_runtime() -> _Runtime | None:
    global _runtime, _unavailable
    with _lock:
        if _runtime is not None or _unavailable is not None:
            return _runtime
        _unavailable = unavailable_reason()
        numba_dir = _numba_dir() if _unavailable is None else None
        if _unavailable is None and numba_dir is None:
            _unavailable = "numba is not installed"
        if _unavailable is None:
            try:
                _runtime = _Runtime(numba_dir, _numba_version())
            except Exception as exc:  # a missing extension, an llvmlite without these calls
                _unavailable = f"runtime: {exc}"
        return _runtime


def threading_layer() -> str | None:
    """The thread pool started here ("tbb", "omp", "workqueue"), or None."""
    return None if _runtime is None else _runtime.threading_layer


# --------------------------------------------------------------------------------------------
# Cache lookup, as numba's FunctionCache does it


def _cache_paths(py_func) -> tuple[str, str] | None:
    """(numba's in-tree cache directory for ``py_func``, its index file name)."""
    source = py_func.__code__.co_filename
    if not os.path.isfile(source):
        return None
    directory = os.path.join(os.path.dirname(os.path.abspath(source)), "__pycache__")
    qualname = py_func.__qualname__.replace("<locals>", "").replace(".", "_")
    module = py_func.__module__.split(".")[-1]
    line = py_func.__code__.co_firstlineno
    base = f"{module}.{qualname}-{line}.py{sys.version_info[0]}{sys.version_info[1]}{sys.abiflags}"
    return directory, f"{base}.nbi"


def load(py_func) -> list[Overload] | None:
    """The cached specialisations of the numba kernel whose Python function is ``py_func``,
    ready to call without numba, or None when numba has to do it."""
    runtime = _get_runtime()
    if runtime is None or py_func.__closure__ is not None:
        return None
    paths = _cache_paths(py_func)
    if paths is None:
        return None
    directory, index_name = paths
    with _lock:
        try:
            return _load(runtime, py_func, directory, index_name)
        except Exception:  # anything unexpected in a cache file: numba reads it instead
            return None


@functools.cache
def _source_hash(path: str, mtime: float, size: int) -> bytes:
    """sha256 of a kernel's source file, numba's cache stamp; read once per file version (a
    module holds several kernels), as numba's ``_hash_source_file`` does."""
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).digest()


def _load(runtime: _Runtime, py_func, directory: str, index_name: str) -> list[Overload] | None:
    with open(os.path.join(directory, index_name), "rb") as f:
        version = pickle.load(f)
        index = f.read()
    if version != runtime.version:
        return None
    stamp, overloads = _unpickle(index)
    source = py_func.__code__.co_filename
    status = os.stat(source)
    if stamp != _source_hash(source, status.st_mtime, status.st_size):
        return None
    code_hashes = (
        hashlib.sha256(py_func.__code__.co_code).hexdigest(),
        hashlib.sha256(b"").hexdigest(),
    )
    found = []
    for (signature, magic, hashes), data_name in overloads.items():
        if tuple(magic) != runtime.magic or tuple(hashes) != code_hashes:
            continue
        with open(os.path.join(directory, data_name), "rb") as f:
            payload = _unpickle(f.read())
        overload = _overload(runtime, directory, tuple(_type_name(t) for t in signature), payload)
        if overload is None:
            return None  # numba would load this one differently: let numba do all of them
        found.append(overload)
    return found or None


def _overload(runtime: _Runtime, directory: str, arg_types, payload) -> Overload | None:
    """Load one cached specialisation (numba's ``CompileResult._rebuild``) into the engine."""
    libdata, fndesc, env, _signature, objectmode, lifted, _typeann, reload_init, referenced = payload
    name, kind, data = libdata
    if kind != "object" or objectmode or lifted:
        return None
    descriptor = fndesc.state[1] if isinstance(fndesc.state, tuple) else fndesc.state
    if _type_name(descriptor["restype"]) not in _SCALAR_RETURNS:
        return None
    mangled = descriptor["mangled_name"]
    if not mangled.startswith("_ZN"):
        return None
    environments = [env, *referenced]
    if any(getattr(e, "where", ("", ""))[1] != "_rebuild_env" or e.args[1] for e in environments):
        return None  # an environment with constants: numba rebuilds those
    for reload in reload_init:
        if getattr(reload, "where", None) != ("numba.core.typed_passes", "_reload_parfors"):
            return None
        runtime.launch_threads()
    object_code, _linking_bitcode = data
    if not runtime.add_object(object_code, (directory, _ENVCONV_KERNEL_CACHE)):
        return None
    for e in environments:
        module_name, _consts, env_name = e.args
        runtime.environment(module_name, env_name)  # kept alive by the runtime
    address = runtime.engine.get_function_address("_ZN7cpython" + mangled[3:])
    if not address:
        return None
    wrapper = ctypes.PYFUNCTYPE(ctypes.py_object, ctypes.py_object, ctypes.py_object, ctypes.py_object)(address)
    runtime.keep_alive.append(wrapper)

    def call(args: tuple):
        return wrapper(None, args, None)

    return Overload(arg_types, call)
