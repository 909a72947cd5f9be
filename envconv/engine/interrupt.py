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
"""

from __future__ import annotations

import os
import signal
import threading

__all__ = ["Interrupted", "install", "exit_status", "describe", "done", "GRACE"]

#: Seconds the main thread has to unwind after a signal before the watchdog ends the process.
GRACE = 0.8

_NAMES = {signal.SIGINT: "interrupted (SIGINT)", signal.SIGTERM: "terminated (SIGTERM)"}
_state = {"signum": None, "handled": False, "prefix": "envconv: error: ", "stderr": 2}
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


def _handler(signum, frame) -> None:
    if _state["signum"] is not None:
        return  # already unwinding; the watchdog ends the process if that takes too long
    _state["signum"] = signum
    raise Interrupted(signum)


def _emergency(signum: int) -> None:
    from ..io.temps import forget, live_temps

    for path in live_temps():
        try:
            os.remove(path)
        except OSError:
            pass
        forget(path)
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
        time.sleep(GRACE)
        _emergency(signum)


def install(sigint: bool = True, quiet: bool = False) -> None:
    """Turn SIGTERM (and SIGINT unless ``sigint`` is False: ignored) into :class:`Interrupted`
    in the main thread, and start the watchdog (silent with ``quiet``: a batch worker, whose
    parent reports). Call once, from the main thread."""
    if threading.current_thread() is not threading.main_thread():
        return
    _state["handled"] = quiet
    try:  # the terminal's stderr, kept: a capture (envconv.io.chatter) may hold descriptor 2
        _state["stderr"] = os.dup(2)
    except OSError:
        pass
    signal.signal(signal.SIGTERM, _handler)
    signal.signal(signal.SIGINT, _handler if sigint else signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):  # POSIX: a batch worker starts with SIGINT blocked
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        read, write = os.pipe()
        os.set_blocking(write, False)
        signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    except (OSError, ValueError):  # no non-blocking pipes here: no watchdog
        return
    threading.Thread(target=_watch, args=(read,), name="envconv-signals", daemon=True).start()
