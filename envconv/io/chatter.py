"""What image libraries print, captured: stdout carries results only, an error stays one line.

OpenImageIO and OpenEXR report some problems by printing them, from C++, on the process's own
file descriptors: a truncated EXR makes OpenEXR print its chunk errors on stderr and
``Warning: Exception raised reading pixel data …`` on *stdout*, where scripts read the list of
written paths. :func:`library_output` points descriptors 1 and 2 at an anonymous temporary
file while a read or write runs, then puts them back and deals with what was caught:

* the block failed with an :class:`~envconv.errors.EnvconvError`: the first meaningful line
  caught (deduplicated, the file name prefix dropped) is folded into the error's one line,
  unless the line already says it;
* the block failed with :class:`MemoryError` (``std::bad_alloc`` from C++ too): an
  :class:`~envconv.errors.ImageIOError` "out of memory" naming the operation;
* the block succeeded: each line caught is logged at debug level (``envconv -vv``).

Lines envconv's own log printed meanwhile (they start ``envconv: ``, and the log handler
writes to descriptor 2 too) are passed on to stderr as they are.

Text that bindings print through Python's ``sys.stdout``/``sys.stderr`` (OpenEXR's module
prints its pixel-read warning so) and Python warnings raised meanwhile (numpy's) are caught
the same way.

Only where envconv owns the process
    Descriptors, ``sys.stdout`` and warning filters belong to the whole process: redirecting
    them from a library call would swallow what the caller's other threads print (a Dask
    worker runs several tasks at once) and race with their own captures. So a capture
    redirects nothing unless the command line has turned capturing on
    (:func:`capture_descriptors`, for its main thread; the batch workers it starts inherit
    the setting). A library caller's process is never touched: errors come from OpenImageIO's
    own ``geterror()``/``has_error`` (each call site checks them), ``MemoryError`` still
    becomes an ``ImageIOError``, and what the C++ libraries print reaches the caller's stderr
    as it would without envconv. Captures nest: only the outermost redirects.
"""

from __future__ import annotations

import atexit
import functools
import io
import logging
import os
import sys
import threading
import warnings
from contextlib import ExitStack, contextmanager, redirect_stderr, redirect_stdout

from ..errors import EnvconvError, ImageIOError

__all__ = ["library_output", "Caught", "meaningful_lines", "fold", "capture_descriptors",
           "capturing"]  # fmt: skip

log = logging.getLogger(__name__)

#: How envconv's own log lines start (the CLI's logging format).
_OWN = "envconv: "
_LOCK = threading.Lock()
_DEPTH = 0
#: At most this much caught output is kept (a library in a loop must not fill the disk or RAM).
_KEEP_BYTES = 64 * 1024
#: Whether captures redirect the process's descriptors (see the module docstring).
_CAPTURE = {"on": False}


def capture_descriptors(on: bool = True) -> bool:
    """Let captures redirect descriptors 1 and 2 (and ``sys.stdout``, ``sys.stderr``, the
    warning filters) in this process's main thread: the command line's choice, for a process
    it owns. Returns the previous setting."""
    previous, _CAPTURE["on"] = _CAPTURE["on"], bool(on)
    return previous


def capturing() -> bool:
    """Whether a capture starting now, in this thread, redirects the descriptors."""
    return _CAPTURE["on"] and threading.current_thread() is threading.main_thread()


class Caught:
    """What a :func:`library_output` block caught: ``text`` from the descriptors and
    ``warnings`` (Python warning messages), filled when the block ends."""

    def __init__(self) -> None:
        self.text = ""
        self.warnings: list[str] = []

    def lines(self, name: str | None = None) -> list[str]:
        """The meaningful lines caught, deduplicated, in order (see :func:`meaningful_lines`),
        but not envconv's own (:meth:`own_lines`)."""
        text = "\n".join(line for line in self.text.splitlines() if not line.startswith(_OWN))
        return meaningful_lines("\n".join([text, *self.warnings]), name)

    def own_lines(self) -> list[str]:
        """Lines envconv's own log printed meanwhile (its handler writes to descriptor 2):
        they are passed on as they are, not taken for library output."""
        return [line for line in self.text.splitlines() if line.startswith(_OWN)]


def meaningful_lines(text: str, name: str | None = None) -> list[str]:
    """The distinct non-blank lines of ``text``, stripped, a ``NAME:`` prefix (the file's path
    or base name, as OpenEXR starts its messages) and a ``Warning:`` prefix dropped."""
    found: list[str] = []
    base = os.path.basename(name) if name else None
    prefixes = [f"{p}:" for p in dict.fromkeys((name, base)) if p] + ["Warning:", "warning:"]
    for line in text.splitlines():
        line = " ".join(line.split())
        for prefix in prefixes:
            if line.startswith(prefix):
                line = line[len(prefix) :].strip()
        if line and line not in found:
            found.append(line)
    return found


def _flush_c_stdio() -> None:
    """Flush C stdio buffers (C++ ``std::cout`` writes through them), so text a library
    printed lands in the capture, not on the real stdout after it is restored."""
    fflush = _c_fflush()
    if fflush is not None:
        fflush(None)


@functools.cache
def _c_fflush():
    import ctypes

    try:
        return ctypes.CDLL(None).fflush
    except (OSError, AttributeError, TypeError):  # no C library by that name (Windows)
        return None


def _flush_python() -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):
            pass


@contextmanager
def _redirected():
    """Descriptors 1 and 2 into a temporary file for the block; yields (the file, or None
    when another capture is already active or the descriptors cannot be duplicated; whether
    this is the outermost capture)."""
    global _DEPTH
    with _LOCK:
        _DEPTH += 1
        outer = _DEPTH == 1
    saved, sink = [], None
    try:
        if outer:
            try:
                sink = _sink()
                _flush_python()
                _flush_c_stdio()
                saved = [os.dup(1), os.dup(2)]
                os.dup2(sink.fileno(), 1)
                os.dup2(sink.fileno(), 2)
            except OSError:
                for fd in saved:
                    os.close(fd)
                saved, sink = [], None
        yield (sink if saved else None), outer
    finally:
        if saved:
            _flush_c_stdio()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
        with _LOCK:
            _DEPTH -= 1


_SINK: tuple[int, object] | None = None


def _sink():
    """This process's capture file, emptied: an unlinked temporary file (never litter), made
    once per process (a forked batch worker makes its own; 0.3 ms saved per file read)."""
    global _SINK
    import tempfile

    if _SINK is None or _SINK[0] != os.getpid():
        _SINK = (os.getpid(), tempfile.TemporaryFile(buffering=0))
        atexit.register(_SINK[1].close)
    sink = _SINK[1]
    os.lseek(sink.fileno(), 0, os.SEEK_SET)
    os.ftruncate(sink.fileno(), 0)
    return sink


def _read_back(sink) -> str:
    if sink is None:
        return ""
    try:
        os.lseek(sink.fileno(), 0, os.SEEK_SET)
        return os.read(sink.fileno(), _KEEP_BYTES).decode("utf-8", "replace")
    except OSError:
        return ""


@contextmanager
def library_output(what: str, path: str | os.PathLike | None = None):
    """Capture library output while the block runs, where the command line has turned
    capturing on (see the module docstring); elsewhere only fold ``MemoryError``.

    Parameters
    ----------
    what : str
        The operation, as an error line starts: ``"cannot read sky.exr"``.
    path : str or path, optional
        The file, whose path (or base name) is dropped from the front of the lines caught.

    Yields
    ------
    Caught
        Filled when the block ends.
    """
    caught = Caught()
    name = os.fspath(path) if path is not None else None
    if not capturing():  # a library caller's process: nothing of it is touched
        try:
            yield caught
        except BaseException as exc:
            folded = fold(exc, what, caught, name)
            if folded is exc:
                raise
            raise folded from exc
        return
    failure = None
    python_text = io.StringIO()  # bindings that print through Python (OpenEXR's py::print)
    with _redirected() as (sink, outer), ExitStack() as streams:
        recorded: list = []
        if outer:  # sys.stdout/sys.stderr and warning filters are process-wide: the outermost
            streams.enter_context(redirect_stdout(python_text))  # capture takes them alone
            streams.enter_context(redirect_stderr(python_text))
            recorded = streams.enter_context(warnings.catch_warnings(record=True))
            warnings.simplefilter("always")
        try:
            try:
                yield caught
            finally:
                caught.warnings = [f"{w.category.__name__}: {w.message}" for w in recorded]
        except BaseException as exc:  # folded below, once the descriptors are back
            failure = exc
    caught.text = _read_back(sink) + "\n" + python_text.getvalue()[:_KEEP_BYTES]
    for line in caught.own_lines():  # envconv's own log lines, swallowed by the capture,
        sys.stderr.write(line + "\n")  # go where its log handler had written them
    if failure is None:
        _report(caught, name)
        return
    folded = fold(failure, what, caught, name)
    if folded is failure:
        raise failure
    raise folded from failure


def _report(caught: Caught, name: str | None) -> None:
    for line in caught.lines(name):
        log.debug("library: %s", line)


def fold(exc: BaseException, what: str, caught: Caught, name: str | None) -> BaseException:
    """The error to raise for ``exc`` raised in a capture: an EnvconvError with the first
    line caught that it does not already say, MemoryError as ImageIOError; others as they are."""
    lines = caught.lines(name)
    if isinstance(exc, MemoryError):
        detail = f" ({lines[0]})" if lines else ""
        return ImageIOError(f"{what}: out of memory{detail}")
    if isinstance(exc, EnvconvError):
        message = str(exc)
        extra = next((line for line in lines if line not in message), None)
        if extra is not None:
            extra = extra if len(extra) <= 200 else extra[:197] + "..."
            return type(exc)(f"{message}; {extra}")
    return exc
