"""SIGINT and SIGTERM: a run ends within a second, with status 130 or 143, leaving no temp file.

:func:`install` (called by the command line, and by batch worker processes) makes both signals
raise :class:`Interrupted` in the main thread, so the run unwinds: writes remove their
temporary files, a batch cancels its queued jobs and writes the report of what finished.
Long kernels run on a helper thread that the main thread waits for in short steps and cancels
when interrupted (:func:`envconv.resample.kernels.resample_rows`).

Code that cannot be interrupted (a write inside OpenImageIO, a read of a huge file) would hold
the run up; a watchdog thread, woken by the signal itself (``signal.set_wakeup_fd``), waits
:data:`GRACE` seconds and then removes this process's temporary files
(:func:`envconv.io.temps.live_temps`), prints the one line and ends the process with the same
status. A second signal during the unwinding is left to the watchdog. The line goes to a copy
of descriptor 2 taken at :func:`install`, so a capture of library output
(:mod:`envconv.io.chatter`, which points descriptor 2 at a file during reads and writes) cannot
swallow it.

A signal that lands while the main thread is importing a module is held back, not raised: an
exception inside the initialisation of a native extension (OpenImageIO's, made with nanobind)
aborts the process (SIGABRT, a core dump instead of one line). The watchdog raises it again
every few milliseconds (``_thread.interrupt_main``) until the import is over. Once the command
has finished (:func:`closing`), a signal no longer interrupts the interpreter's own ending.

A batch worker (:func:`die_with_parent`) asks Linux for SIGTERM when its parent dies, so a
``kill -9`` of ``envconv batch`` stops its workers at once, quietly, their temporary files
removed, instead of letting them finish their jobs for no one and fail to report them.
"""

from __future__ import annotations

import _thread
import os
import signal
import sys
import threading

__all__ = ["Interrupted", "install", "exit_status", "describe", "done", "report", "closing",
           "die_with_parent", "remove_live_temps", "GRACE"]  # fmt: skip

#: Seconds the main thread has to unwind after a signal before the watchdog ends the process.
GRACE = 0.8

_NAMES = {signal.SIGINT: "interrupted (SIGINT)", signal.SIGTERM: "terminated (SIGTERM)"}
_PR_SET_PDEATHSIG = 1
#: Seconds between the watchdog's attempts to raise a signal held back during an import.
_RETRY = 0.01
_state = {"signum": None, "handled": False, "prefix": "envconv: error: ", "stderr": 2,
          "held": None, "closing": False, "installed": False}  # fmt: skip
_report_lock = threading.Lock()


class Interrupted(KeyboardInterrupt):
    """The run was stopped by a signal; ``signum`` is SIGINT or SIGTERM."""

    def __init__(self, signum: int = signal.SIGINT) -> None:
        super().__init__(_NAMES.get(signum, f"stopped by signal {signum}"))
        self.signum = signum


def exit_status(exc: BaseException | None = None) -> int:
    """128 + the signal number: 130 for SIGINT (also a plain KeyboardInterrupt), 143 for SIGTERM."""
    return 128 + int(getattr(exc, "signum", signal.SIGINT))


def describe(exc: BaseException | None = None) -> str:
    """The one-line reason: ``interrupted (SIGINT)`` or ``terminated (SIGTERM)``."""
    return _NAMES.get(getattr(exc, "signum", signal.SIGINT), "interrupted")


def done() -> bool:
    """Claim the report of the interruption: True for the first caller (who prints the one
    line), False once the main thread or the watchdog has; the watchdog then only ends the
    process."""
    with _report_lock:
        first = not _state["handled"]
        _state["handled"] = True
    return first


def report(exc: BaseException | None = None) -> int:
    """Remove this process's unfinished temporary files, print the one line of an
    interruption (unless the watchdog has) on the stderr kept at :func:`install`; return the
    exit status. For code that runs before click is loaded."""
    remove_live_temps()
    if done():
        try:
            os.write(_state["stderr"], f"{_state['prefix']}{describe(exc)}\n".encode())
        except OSError:
            pass
    return exit_status(exc)


def closing() -> None:
    """The command has finished: a signal from now on no longer raises (the watchdog still
    ends a process whose ending hangs)."""
    _state["closing"] = True


def _importing(frame) -> bool:
    """Whether ``frame`` runs inside an import (a frame of importlib's bootstrap below it)."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def _handler(signum, frame) -> None:
    if _state["signum"] is not None or _state["closing"]:
        return  # already unwinding, or done; the watchdog ends a process that takes too long
    if _importing(frame):
        _state["held"] = signum  # raised again by the watchdog once the import is over
        return
    _state["signum"] = signum
    raise Interrupted(signum)


def remove_live_temps() -> None:
    """Remove this process's unfinished temporary files (:func:`envconv.io.temps.live_temps`):
    what an interrupted run leaves when the signal lands between a temp's creation and the
    code that would discard it."""
    from ..io.temps import forget, live_temps

    for path in live_temps():
        try:
            os.remove(path)
        except OSError:
            pass
        forget(path)


def _emergency(signum: int) -> None:
    remove_live_temps()
    if done():
        try:
            os.write(
                _state["stderr"],
                f"{_state['prefix']}{_NAMES.get(signum, 'interrupted')}\n".encode(),
            )
        except OSError:
            pass
    os._exit(128 + signum)


def _watch(fd: int) -> None:
    import time

    while True:
        try:
            data = os.read(fd, 1)
        except InterruptedError:
            continue
        except OSError:
            return
        if not data:
            return
        signum = data[0]
        if signum not in _NAMES:
            continue
        end = time.monotonic() + GRACE
        while time.monotonic() < end:
            time.sleep(_RETRY)
            held = _state["held"]
            if held is not None and _state["signum"] is None and not _state["closing"]:
                _thread.interrupt_main(held)  # the handler runs again in the main thread
        _emergency(signum)


def install(sigint: bool = True, quiet: bool = False) -> None:
    """Turn SIGTERM (and SIGINT unless ``sigint`` is False: ignored) into :class:`Interrupted`
    in the main thread, and start the watchdog (silent with ``quiet``: a batch worker, whose
    parent reports). Call from the main thread; a second call changes nothing.

    The handlers are set last, so nothing here can be interrupted half-way; a signal that
    was blocked (a batch worker starts with SIGINT blocked) or recorded before (see
    :mod:`envconv.__main__`) is raised on return: call it inside the ``try`` that handles
    :class:`Interrupted`."""
    if threading.current_thread() is not threading.main_thread() or _state["installed"]:
        return
    _state["installed"], _state["handled"] = True, quiet
    try:  # the terminal's stderr, kept: a capture (envconv.io.chatter) may hold descriptor 2
        _state["stderr"] = os.dup(2)
    except OSError:
        pass
    try:
        read, write = os.pipe()
        os.set_blocking(write, False)
        signal.set_wakeup_fd(write, warn_on_full_buffer=False)
        threading.Thread(target=_watch, args=(read,), name="envconv-signals", daemon=True).start()
    except (OSError, ValueError):  # no non-blocking pipes here: no watchdog
        pass
    signal.signal(signal.SIGTERM, _handler)
    signal.signal(signal.SIGINT, _handler if sigint else signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):  # POSIX: a batch worker starts with SIGINT blocked
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})


def die_with_parent(parent: int | None) -> None:
    """Have Linux send this process SIGTERM when its parent (pid ``parent``) dies
    (``prctl(PR_SET_PDEATHSIG)``); a parent already gone is a SIGTERM now. Elsewhere nothing
    is done: the worker then notices at its next message."""
    if parent is None or not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # died before the request: nobody would send it
        os.kill(os.getpid(), signal.SIGTERM)
