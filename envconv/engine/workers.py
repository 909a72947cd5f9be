"""Worker processes for ``batch -j N``: one job per worker at a time, deaths and interruptions
contained.

* Each worker is a ``spawn``-ed process that receives one job at a time over a pipe and
  sends back its record (:func:`envconv.engine.batch.run_job`, which never raises for a bad input).
  Nothing is queued ahead in a worker, so an interruption has nothing to drain.
* A worker that dies (killed by the OOM killer, a codec crash) costs only the job it was
  running: that job is run again once on a fresh worker; if that worker dies too the job
  fails with the cause ("worker died (killed by SIGKILL)"). The other jobs go on. Every death
  is listed in the returned events (and so in the batch report).
* A worker that dies before it is ready (its imports or its set-up failed: a script that
  starts a batch without ``if __name__ == "__main__":``, which every spawned worker runs again,
  or a broken environment) would die again on every start: the batch stops at once with
  :class:`WorkerStartError`, one line saying why. What a worker writes on stderr goes through
  this process (:class:`_Stderr`): kept until the worker is ready, so that its last line gives
  the cause instead of a traceback per worker on the terminal, and passed on after.
* A worker whose parent dies (``kill -9`` of ``envconv batch``) gets SIGTERM from Linux
  (:func:`envconv.engine.interrupt.die_with_parent`) and ends quietly, its temporary file
  removed; elsewhere it ends at its next message to the dead parent, as quietly.
* SIGINT/SIGTERM in this process (:mod:`envconv.engine.interrupt`) stops handing out jobs, sends
  SIGTERM to the workers (which remove their temporary files and exit; they ignore SIGINT,
  so the terminal's Ctrl-C reaches them only through this process), kills any that have not
  gone after :data:`STOP_WAIT` seconds, removes their temporary files, and re-raises.
"""

from __future__ import annotations

import logging
import os
import re
import signal
import sys
import threading
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from ..errors import EnvconvError

__all__ = ["run_pool", "STOP_WAIT", "WorkerStartError"]

log = logging.getLogger(__name__)

#: Seconds interrupted workers get to remove their temporary files before they are killed.
STOP_WAIT = 0.3
#: The index a worker sends, with its pid, once it has imported everything and is ready.
_READY = -1
#: Bytes of a starting worker's stderr kept to find the cause of its death.
_KEPT = 1 << 16
#: The last line of a Python traceback: the exception's name and message.
_EXCEPTION_LINE = re.compile(r"^(?:[\w.]+\.)?(\w+(?:Error|Exception|Exit|Interrupt)): ?(.*)$")


class WorkerStartError(EnvconvError):
    """A batch worker process died before it was ready: no worker can run the jobs."""


class _Stderr:
    """A worker's stderr: a pipe this process reads on a thread. Until the worker is ready what
    it writes is kept, the tail of it, to say why it died; after, it is passed on to this
    process's stderr as it comes."""

    def __init__(self) -> None:
        self.read_fd, self.write_fd = os.pipe()
        self.kept = bytearray()
        self.ready = False
        self.lock = threading.Lock()
        self.thread = threading.Thread(target=self._pump, name="envconv-worker-stderr",
                                       daemon=True)  # fmt: skip

    def _pump(self) -> None:
        try:
            while chunk := os.read(self.read_fd, 65536):
                with self.lock:
                    if self.ready:
                        _write_all(2, chunk)
                    else:
                        self.kept += chunk
                        del self.kept[:-_KEPT]
        except OSError:
            pass
        finally:
            os.close(self.read_fd)

    def set_ready(self) -> None:
        """The worker is ready: pass on what it wrote so far and from now on."""
        with self.lock:
            self.ready = True
            kept, self.kept = bytes(self.kept), bytearray()
        if kept:
            _write_all(2, kept)

    def cause(self) -> str:
        """The one line that says why a worker died before it was ready: the last exception
        line of its traceback (else its last line), once it has all been read."""
        self.thread.join(1.0)
        with self.lock:
            lines = [ln.strip() for ln in self.kept.decode("utf-8", "replace").splitlines()]
        lines = [ln for ln in lines if ln]
        for line in reversed(lines):
            match = _EXCEPTION_LINE.match(line)
            if match:
                return f"{match.group(1)}: {match.group(2)}".rstrip(": ")
        return lines[-1] if lines else "it printed nothing"


def _write_all(fd: int, data: bytes) -> None:
    try:
        while data:
            data = data[os.write(fd, data) :]
    except OSError:  # stderr closed: nothing to pass on to
        pass


def _worker_main(conn, call, init) -> None:
    """A worker: ``init()``, then run ``call(job)`` for each (index, job) received and send
    back (index, record). Its parent gone (``kill -9``: SIGTERM by :func:`die_with_parent`,
    or a closed pipe), it ends quietly: no one is left to report to."""
    import multiprocessing

    from .interrupt import die_with_parent, install

    try:
        install(sigint=False, quiet=True)
        parent = multiprocessing.parent_process()
        die_with_parent(parent.pid if parent is not None else None)
        init()
        try:
            conn.send((_READY, os.getpid()))
        except OSError:  # the parent died while this worker started
            return
        while True:
            try:
                message = conn.recv()
            except (EOFError, OSError):
                return
            if message is None:
                return
            index, job = message
            record = call(job)
            try:
                conn.send((index, record))
            except OSError:  # BrokenPipeError: the parent died while the job ran
                return
    except KeyboardInterrupt:  # SIGTERM from the parent or at its death: temps are removed
        os._exit(128 + signal.SIGTERM)


@dataclass
class _Worker:
    process: Any
    conn: Any
    stderr: _Stderr
    index: int | None = None
    ready: bool = False


def _cause(exitcode: int | None) -> str:
    if exitcode is not None and exitcode < 0:
        try:
            return f"killed by {signal.Signals(-exitcode).name}"
        except ValueError:
            return f"killed by signal {-exitcode}"
    return f"exit status {exitcode}"


class _Pool:
    def __init__(self, jobs, workers: int, finish, call, init, failed, outputs) -> None:
        import multiprocessing

        # A forked child would inherit the parent's libraries' thread pools half-copied.
        self.context = multiprocessing.get_context("spawn")
        self.jobs, self.call, self.init = jobs, call, init
        self.finish, self.failed, self.outputs = finish, failed, outputs
        self.pending: deque[int] = deque(range(len(jobs)))
        self.attempts = [0] * len(jobs)
        self.notes: dict[int, str] = {}
        self.events: list[str] = []
        self.workers = [self._start() for _ in range(min(workers, len(jobs)))]

    def _start(self) -> _Worker:
        mine, theirs = self.context.Pipe()
        process = self.context.Process(target=_worker_main, args=(theirs, self.call, self.init),
                                       name="envconv-worker", daemon=True)  # fmt: skip
        # SIGINT stays blocked in the new worker until it ignores it (envconv.engine.interrupt), so a
        # Ctrl-C while it starts reaches only this process.
        mask = getattr(signal, "pthread_sigmask", None)
        blocked = mask(signal.SIG_BLOCK, {signal.SIGINT}) if mask else None
        stderr = _Stderr()
        try:
            _start_with_stderr(process, stderr.write_fd)
        finally:
            if mask:
                mask(signal.SIG_SETMASK, blocked)
            os.close(stderr.write_fd)
        stderr.thread.start()
        theirs.close()
        worker = _Worker(process, mine, stderr)
        self._dispatch(worker)
        return worker

    def _dispatch(self, worker: _Worker) -> None:
        worker.index = None
        if not self.pending:
            return
        index = self.pending.popleft()
        try:
            worker.conn.send((index, self.jobs[index]))
        except OSError:  # died before it took the job: the job has not run
            self.pending.appendleft(index)
            return
        worker.index = index
        self.attempts[index] += 1

    def run(self) -> list[str]:
        from multiprocessing.connection import wait

        while any(w.index is not None for w in self.workers):
            busy = [w for w in self.workers if w.index is not None]
            ready = set(wait([w.conn for w in busy] + [w.process.sentinel for w in busy]))
            for worker in busy:
                if worker.conn in ready or worker.process.sentinel in ready:
                    self._collect(worker)
        self._close()
        return self.events

    def _collect(self, worker: _Worker) -> None:
        try:
            index, record = worker.conn.recv()
        except (EOFError, OSError):
            index = None
        if index is None:  # (outside the except: a start failure is not "during" an EOFError)
            self._died(worker)
            return
        if index == _READY:
            worker.ready = True
            worker.stderr.set_ready()
            return
        if index in self.notes:
            record = {**record, "note": self.notes[index]}
        self.finish(index, record)
        self._dispatch(worker)

    def _died(self, worker: _Worker) -> None:
        """Replace a dead worker; run its job once more, or fail it after a second death."""
        worker.process.join(1.0)
        cause = _cause(worker.process.exitcode)
        worker.conn.close()
        if not worker.ready and (worker.process.exitcode or 0) >= 0:
            raise WorkerStartError(_start_failure(worker, cause))
        index, name = worker.index, None
        if index is not None:
            name = self.jobs[index].name
            if self.attempts[index] < 2:
                self.pending.appendleft(index)
                self.notes[index] = f"worker died ({cause}); run again on a fresh worker"
            else:
                self.finish(index, self.failed(self.jobs[index], f"worker died twice ({cause})"))
        event = f"worker {worker.process.pid} died ({cause})" + (f" running {name}" if name else "")
        log.warning("%s", event)
        self.events.append(event)
        self.workers.remove(worker)
        if self.pending:
            self.workers.append(self._start())

    def _close(self) -> None:
        for worker in self.workers:
            try:
                worker.conn.send(None)
            except OSError:
                pass
        for worker in self.workers:
            worker.process.join(5)
            if worker.process.is_alive():
                worker.process.kill()

    def stop(self) -> None:
        """Interrupted: SIGTERM every worker, kill those still there after STOP_WAIT, and
        remove the temporary files of the jobs that were running."""
        import time

        from ..io.sets import clean_folder

        for worker in self.workers:
            if worker.process.is_alive():
                worker.process.terminate()
        deadline = time.monotonic() + STOP_WAIT
        for worker in self.workers:
            worker.process.join(max(0.0, deadline - time.monotonic()))
            if worker.process.is_alive():
                worker.process.kill()
                worker.process.join(0.2)
            self._drain(worker)
        for folder in self._folders():
            clean_folder(folder)

    def _drain(self, worker: _Worker) -> None:
        """Take the record a stopped worker sent before it stopped: that job did finish."""
        try:
            if worker.index is not None and worker.conn.poll():
                index, record = worker.conn.recv()
                self.finish(index, record)
                worker.index = None
        except (EOFError, OSError, ValueError):
            pass

    def _folders(self) -> set[str]:
        folders = set()
        for worker in self.workers:
            if worker.index is not None:
                try:
                    outputs = self.outputs(self.jobs[worker.index])
                except Exception:  # a job without a plannable output: nothing to clean
                    continue
                folders.update(os.path.dirname(p) for p in outputs)
        return folders


def _start_with_stderr(process, fd: int) -> None:
    """Start ``process`` with ``fd`` as its stderr: a spawned process inherits descriptor 2,
    so it is pointed there for the moment of the start (this process's own stderr, flushed
    first, is back when ``start`` returns)."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        os.dup2(fd, 2)
        process.start()
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _start_failure(worker: _Worker, cause: str) -> str:
    """The one line of a worker that died before it was ready. A spawned worker runs the main
    script again (as ``__mp_main__``) to find what the jobs refer to; a script that starts the
    batch outside ``if __name__ == "__main__":`` starts it again there, which multiprocessing
    refuses ("... before the current process has finished its bootstrapping phase")."""
    why = worker.stderr.cause()
    with worker.stderr.lock:
        text = worker.stderr.kept.decode("utf-8", "replace")
    if "bootstrapping phase" in text:
        script = os.path.basename(getattr(sys.modules.get("__main__"), "__file__", "") or "")
        return (f"batch workers cannot start: each worker runs the script {script or ''} again "
                "as it starts, and the script starts the batch again; put the code that starts "
                'the batch under `if __name__ == "__main__":` (docs/python.md)')  # fmt: skip
    return f"batch workers cannot start: a worker died before it was ready ({cause}): {why}"


def run_pool(
    jobs: Sequence[Any],
    workers: int,
    finish: Callable[[int, dict[str, Any]], None],
    call: Callable[[Any], dict[str, Any]],
    init: Callable[[], None],
    failed: Callable[[Any, str], dict[str, Any]],
    outputs: Callable[[Any], list[str]],
) -> list[str]:
    """Run ``call(job)`` for every job on ``workers`` processes and ``finish(index, record)``
    as each ends; returns the events (worker deaths) for the report.

    ``call`` and ``init`` (run once in each worker) must be picklable (module-level functions
    or partials of them). ``failed(job, reason)`` makes the record of a job whose worker died
    twice; ``outputs(job)`` names a job's output files, whose folders are cleaned of the
    temporary files of workers killed on an interruption (KeyboardInterrupt: re-raised).
    """
    pool = _Pool(jobs, workers, finish, call, init, failed, outputs)
    try:
        return pool.run()
    except BaseException:
        pool.stop()
        raise
