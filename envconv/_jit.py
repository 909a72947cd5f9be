"""All numba options in one place.

Kernels are compiled with ``cache=True`` so that only the first run pays for compilation.
HDR images carry inf and nan, so the fast-math flags exclude ``nnan`` and ``ninf``.

Kernel modules take ``jit``, ``jit_inline``, ``jit_parallel``, ``intrinsic`` and ``prange``
from here, never from numba: in a process the command line runs, numba is not imported at all
while every kernel called is found in numba's cache. Such a kernel runs from numba's cached
machine code through :mod:`envconv._cached_kernels` (0.15–0.2 s less start-up). The first call
that needs numba itself (a cache miss, arguments of a new type) imports it and turns every
deferred kernel into numba's dispatcher (:class:`_Deferred`, :func:`import_numba`).
``ENVCONV_IMPORT_NUMBA=1`` imports numba at once, as a library import always does.

Developers: numba checks a cached kernel against its own source file only. After editing a
helper in another module (a layout's map, ``kernels/cells.py``...), delete the stale caches:
``find envconv -name '*.nbi' -delete -o -name '*.nbc' -delete``.

Loading a cached kernel: numba's cache loader first "refreshes" its compiler, importing and
installing every typing and lowering registry (numpy, linalg, random, typed containers...):
0.12–0.15 s of a one-shot ``envconv convert`` on this machine, spent on nothing the machine
code needs. envconv's own dispatchers load from the cache after starting numba's runtime
(NRT) alone, which is what the code calls into; the parallel thread pool is started by the
cached code's own reload hook as usual. A cache miss compiles as usual, and numba's compiler
then refreshes itself. Dispatchers of other packages are not touched.

The first call of a dispatcher types its arguments in Python; numba's rule for an ndarray first
asks whether it is a ``numpy.ma.MaskedArray``, which imports numpy.ma: 0.013 s. envconv's
dispatchers type a plain ndarray with the rest of that same rule (:func:`_type_plain_arrays`).

Starting NRT compiles its few LLVM functions (atomic reference counts) afresh in every process:
0.02 s. envconv keeps their machine code next to its kernels' cache, keyed like numba's own
entries by numba's version and the host CPU (:func:`_start_runtime`).

Importing numba imports PyYAML, when installed, for a ``.numba_config.yaml`` that is seldom
there: 0.01–0.02 s. The command line imports numba without it when there is no such file, and
numba imports PyYAML the first time one appears (:func:`_import_numba`).
"""

import contextlib
import hashlib
import importlib.util
import os
import pickle
import sys
import threading


def _import_numba():
    """Import numba; in envconv's command line, without PyYAML unless it is needed.

    numba imports PyYAML at import time only to read a ``.numba_config.yaml`` in the working
    directory, which it looks for again whenever it compiles. When the file is not there, the
    import of PyYAML is refused for as long as numba's own import lasts (numba then records
    that it has no PyYAML); afterwards, if PyYAML is installed, numba's config is told it has
    it and gets a stand-in that imports it on first use. Refusing an import is seen by every
    thread, so this is done only in a process the command line runs (``envconv.
    _COMMAND_LINE_PROCESS``), never in someone else's program. With the file there, or
    PyYAML or numba already imported, numba is imported as usual.
    """
    if "numba" in sys.modules:
        return sys.modules["numba"]
    skip_yaml = (
        getattr(sys.modules.get("envconv"), "_COMMAND_LINE_PROCESS", False) is True
        and "yaml" not in sys.modules
        and not os.path.isfile(".numba_config.yaml")
    )
    if skip_yaml:
        sys.modules["yaml"] = None  # "import yaml" raises ImportError
    try:
        import numba
    finally:
        if skip_yaml and "yaml" in sys.modules and sys.modules["yaml"] is None:
            del sys.modules["yaml"]
    config = getattr(getattr(numba, "core", None), "config", None)
    if skip_yaml and getattr(config, "_HAVE_YAML", True) is False and importlib.util.find_spec("yaml"):
        config.yaml = _YamlOnDemand()
        config._HAVE_YAML = True
    return numba


class _YamlOnDemand:
    """What numba's config uses of PyYAML, importing it on first use."""

    @staticmethod
    def safe_load(stream):
        import yaml

        return yaml.safe_load(stream)


def _deferring() -> bool:
    """Whether this process defers numba (see :class:`_Deferred`): only a process the command
    line runs, with numba not yet imported, a numba version and configuration that
    :mod:`envconv._cached_kernels` knows, and no ``ENVCONV_IMPORT_NUMBA=1``."""
    if getattr(sys.modules.get("envconv"), "_COMMAND_LINE_PROCESS", False) is not True:
        return False
    if os.environ.get("ENVCONV_IMPORT_NUMBA") or "numba" in sys.modules:
        return False
    from . import _cached_kernels

    return _cached_kernels.unavailable_reason() is None


#: numba, once imported (at once, unless this process defers it: see :class:`_Deferred`).
numba = None if _deferring() else _import_numba()

__all__ = ["jit", "jit_inline", "jit_parallel", "intrinsic", "prange", "FASTMATH", "import_numba", "preload"]

_materialize_lock = threading.RLock()
_deferred: list["_Deferred"] = []
_rebound = False  # import_numba has made every deferred object real


class _Deferred:
    """A kernel, or another numba object, made only when numba is needed.

    In a process the command line runs, importing numba (0.15–0.2 s) is put off: a kernel is
    first looked up in numba's cache and, when its arguments match a cached specialisation,
    run from that machine code without numba (:mod:`envconv._cached_kernels`). Anything else (a
    cache miss, other argument types, an attribute of the dispatcher) imports numba and makes
    every deferred object real at once (:func:`import_numba`): numba types a kernel's globals
    when it compiles it, so they must all be numba's own objects by then.
    """

    def __init__(self, py_func, make):
        self.py_func = py_func
        self._make = make  # numba -> the real object
        self._real = None
        self._overloads = None  # cached specialisations, once looked up
        self.__name__ = getattr(py_func, "__name__", "deferred")
        self.__qualname__ = getattr(py_func, "__qualname__", self.__name__)
        self.__doc__ = getattr(py_func, "__doc__", None)
        self.__module__ = getattr(py_func, "__module__", __name__)
        _deferred.append(self)

    def __call__(self, *args, **kwargs):
        real = self._real
        if real is None:
            if not kwargs:
                call = self._cached_call(args)
                if call is not None:
                    return call(args)
            import_numba()
            real = self._real
        return real(*args, **kwargs)

    def _cached_overloads(self):
        """The kernel's specialisations in numba's cache, loaded on first use (empty: none
        that can run without numba)."""
        if self._overloads is None:
            from . import _cached_kernels

            self._overloads = _cached_kernels.load(self.py_func) or ()
        return self._overloads

    def _cached_call(self, args):
        """The cached specialisation for exactly these argument types, or None."""
        overloads = self._cached_overloads()
        if not overloads:
            return None
        from ._cached_kernels import arg_type_name

        types = tuple(arg_type_name(value) for value in args)
        for overload in overloads:
            if overload.arg_types == types:
                return overload.call
        return None

    def __getattr__(self, name):
        if name.startswith("__") or name == "_real":
            raise AttributeError(name)
        import_numba()
        return getattr(self._real, name)

    def __repr__(self):
        return f"<deferred numba object {self.__qualname__}>"


def import_numba():
    """Import numba (if this process deferred it) and make every deferred object real.

    Every global that names a deferred object, in envconv's modules and in the modules that
    defined deferred kernels, is rebound to the real one. A thread pool that
    :mod:`envconv._cached_kernels` started becomes numba's own. Once done, this returns at once
    (no object is deferred once numba is imported)."""
    global numba, prange, _rebound
    with _materialize_lock:
        if _rebound:
            return numba
        if numba is None:
            numba = _import_numba()
            _adopt_thread_pool()
            prange = numba.prange
        for deferred in _deferred:
            if deferred._real is None:
                deferred._real = deferred._make(numba)
        placeholders = {id(deferred): (deferred, deferred._real) for deferred in _deferred}
        placeholders[id(_PRANGE)] = (_PRANGE, numba.prange)
        homes = {getattr(deferred.py_func, "__module__", None) for deferred in _deferred}
        for name, module in list(sys.modules.items()):
            if (name == "envconv" or name.startswith("envconv.") or name in homes) and name != __name__:
                namespace = getattr(module, "__dict__", {})
                for key, value in list(namespace.items()):
                    placeholder, real = placeholders.get(id(value), (None, None))
                    if value is placeholder:
                        namespace[key] = real
        _rebound = True
    return numba


def preload(*kernels) -> None:
    """Look up deferred kernels' cached machine code now rather than at their first call, for
    a caller with time to spare (a one-shot command, while its input decodes on another
    thread). Kernels numba already handles, and a process that imports numba, are left alone."""
    for kernel in kernels:
        if isinstance(kernel, _Deferred) and kernel._real is None:
            kernel._cached_overloads()


def _adopt_thread_pool() -> None:
    """Tell numba about the thread pool and extension modules loaded without it, as numba's own
    ``_launch_threads`` would have left them."""
    cached = sys.modules.get("envconv._cached_kernels")
    if cached is None or cached._runtime is None:
        return
    for name, module in list(sys.modules.items()):  # numba's packages now exist: link them
        parent, _, child = name.rpartition(".")
        if name.startswith("numba.") and parent in sys.modules and not hasattr(sys.modules[parent], child):
            setattr(sys.modules[parent], child, module)
    runtime = cached._runtime
    if runtime.threading_layer is None:
        return
    from numba.np.ufunc import parallel

    with parallel._backend_init_thread_lock:
        if not parallel._is_initialized:
            parallel._load_threading_functions(runtime.thread_library)
            parallel._threading_layer = runtime.threading_layer
            parallel._is_initialized = True


class _Placeholder:
    def __init__(self, name):
        self.name = name

    def __repr__(self):
        return f"<deferred numba.{self.name}>"


#: ``prange`` for kernel modules: numba's, or a placeholder that :func:`import_numba` replaces.
_PRANGE = _Placeholder("prange")
prange = _PRANGE if numba is None else numba.prange

#: LLVM fast-math flags that are safe with inf/nan data.
FASTMATH = {"nsz", "arcp", "contract", "afn", "reassoc"}


def _load_cached_without_refresh(dispatcher):
    """Make ``dispatcher`` load cached machine code without refreshing numba's compiler.

    numba's ``Cache.load_overload`` is ``target_context.refresh()`` followed by
    ``_load_overload``; the refresh only matters for compiling. Where this numba's cache lacks
    those internals, the dispatcher is left as it is."""
    cache = getattr(dispatcher, "_cache", None)
    load = getattr(cache, "_load_overload", None)
    guard = getattr(cache, "_guard_against_spurious_io_errors", None)
    if load is None or guard is None:
        return dispatcher

    def load_overload(sig, target_context):
        _start_runtime(target_context, getattr(cache, "_cache_path", None))
        with guard(), _linking_bitcode_on_demand():
            return load(sig, target_context)
        return None  # the guard swallowed a spurious I/O error: compile instead

    cache.load_overload = load_overload
    return _type_plain_arrays(dispatcher)


@contextlib.contextmanager
def _linking_bitcode_on_demand():
    """Within: a library loaded from cached machine code parses its linking bitcode when first
    linked into a compilation, not at load.

    numba keeps, beside a cached library's machine code, its LLVM bitcode for linking into
    other libraries being compiled, and parses it and records its symbols at every load: 0.035 s
    for the resampling kernel, which is called, never linked. Only an uncached compilation that
    calls a loaded function links it (numba's ``_get_module_for_linking``). Any other kind of
    library, or a numba without these internals, loads as numba does.
    """
    from numba.core import codegen

    library_class = getattr(codegen, "CPUCodeLibrary", None)
    original = getattr(library_class, "_unserialize", None)
    needed = ("create_library", "_engine")
    if original is None or not hasattr(library_class, "_get_module_for_linking"):
        yield
        return

    def unserialize(cls, codegen_, state):
        name, kind, data = state
        if kind != "object" or not all(hasattr(codegen_, n) for n in needed):
            return original.__func__(cls, codegen_, state)
        object_code, linking_bitcode = data
        library = codegen_.create_library(name)
        library.enable_object_caching()
        library._set_compiled_object(object_code)
        library._finalize_final_module()
        engine = codegen_._engine
        for_linking = library._get_module_for_linking
        pointer_to_function = library.get_pointer_to_function

        def parse_for_linking():
            if library._shared_module is None:  # what numba's load does, done now
                from llvmlite import binding

                library._shared_module = binding.parse_bitcode(linking_bitcode)
                engine._load_defined_symbols(library._shared_module)

        def get_module_for_linking():
            parse_for_linking()
            return for_linking()

        def get_pointer_to_function(name):
            # numba first checks the name against the symbols recorded from the bitcode; the
            # machine code answers that itself (0: not there, then numba's own way).
            address = engine.get_function_address(name)
            if address:
                return address
            parse_for_linking()
            return pointer_to_function(name)

        library.get_pointer_to_function = get_pointer_to_function
        library._get_module_for_linking = get_module_for_linking
        return library

    library_class._unserialize = classmethod(unserialize)
    try:
        yield
    finally:
        library_class._unserialize = original


def _type_plain_arrays(dispatcher):
    """Type an argument that is exactly ``numpy.ndarray`` as numba does, without importing
    numpy.ma for its MaskedArray check (a subclass, or anything else, goes to numba)."""
    original = getattr(dispatcher, "typeof_pyval", None)
    if original is None or not hasattr(dispatcher, "_types_active_call"):
        return dispatcher
    import numpy as np
    from numba.core import types
    from numba.np import numpy_support

    def typeof_pyval(value):
        if type(value) is not np.ndarray:
            return original(value)
        try:
            dtype = numpy_support.from_dtype(value.dtype)
        except Exception:  # an unsupported dtype: numba says why
            return original(value)
        layout = numpy_support.map_layout(value)
        found = types.Array(dtype, value.ndim, layout, readonly=not value.flags.writeable)
        dispatcher._types_active_call.add(found)  # as numba's typeof_pyval does
        return found

    dispatcher.typeof_pyval = typeof_pyval
    return dispatcher


def _start_runtime(target_context, cache_dir) -> None:
    """Start numba's runtime (once per process), its LLVM functions loaded from ``cache_dir``.

    The first process compiles them as numba does and saves their machine code there; later
    ones load it. A file that cannot be read, written or loaded just means compiling again.
    """
    from numba.core.runtime import nrtdynmod, rtsys

    if rtsys._init or cache_dir is None:
        rtsys.initialize(target_context)
        return
    compile_nrt = nrtdynmod.compile_nrt_functions

    def load_or_compile(ctx):
        codegen = ctx.codegen()
        key = repr((numba.__version__, codegen.magic_tuple())).encode()
        path = os.path.join(cache_dir, f"nrt-{hashlib.sha256(key).hexdigest()[:16]}.nbo")
        try:
            with open(path, "rb") as f:
                return codegen.unserialize_library(pickle.load(f))
        except Exception:  # absent, unreadable or stale: compile
            pass
        create = getattr(nrtdynmod, "create_nrt_module", None)
        if create is None:
            return compile_nrt(ctx)
        ir_module, library = create(ctx)  # what compile_nrt does, keeping the machine code
        library.enable_object_caching()
        library.add_ir_module(ir_module)
        library.finalize()
        temporary = f"{path}.{os.getpid()}.tmp"
        try:
            state = pickle.dumps(library.serialize_using_object_code())
            os.makedirs(cache_dir, exist_ok=True)
            with open(temporary, "wb") as f:
                f.write(state)
            os.replace(temporary, path)
        except Exception:  # a read-only install: compile in every process
            if os.path.exists(temporary):
                os.remove(temporary)
        return library

    nrtdynmod.compile_nrt_functions = load_or_compile
    try:
        rtsys.initialize(target_context)
    finally:
        nrtdynmod.compile_nrt_functions = compile_nrt


def _dispatcher(fn, **options):
    """numba's dispatcher for ``fn``, loading from its cache the lean way; deferred while this
    process defers numba."""

    def make(numba_module):
        dispatcher = numba_module.njit(cache=True, fastmath=set(FASTMATH), error_model="numpy", **options)
        return _load_cached_without_refresh(dispatcher(fn))

    return make(numba) if numba is not None else _Deferred(fn, make)


def jit(fn):
    """Compile a scalar helper or serial kernel (inlined into its callers by LLVM)."""
    return _dispatcher(fn)


def jit_inline(fn):
    """Compile a helper that takes arrays, inlined into its callers at numba IR level.

    A call to a separately compiled function that receives arrays costs an atomic reference
    count increment and decrement per array; in a per-sample loop that both threads share,
    that dominates the run time. Inlining removes the call and the reference counting.
    """
    return _dispatcher(fn, inline="always")


def jit_parallel(fn):
    """Compile a kernel whose outer ``prange`` loop runs across all cores."""
    return _dispatcher(fn, parallel=True)


def intrinsic(fn):
    """numba's ``@intrinsic`` (deferred while this process defers numba)."""

    def make(numba_module):
        from numba.core.extending import intrinsic as make_intrinsic

        return make_intrinsic(fn)

    return make(numba) if numba is not None else _Deferred(fn, make)
