"""Batch conversion: one pipeline recipe run over many inputs, locally or on a Dask cluster.

Each input is one *job*: the recipe (:class:`envconv.engine.pipeline.Pipeline`) bound to that file. A
job never raises: it returns a record ``{"input", "status", "outputs", "seconds", "error",
"timings", "maps"}`` with status ``done``, ``skipped`` or ``failed``, so one bad file never
stops the batch (``timings`` and ``maps``: :mod:`envconv.engine.records`).

Engines
-------
* ``jobs=1``: in this process; the kernels use every core (:func:`envconv.resample.kernels.get_threads`).
* ``jobs=N``: N worker processes (``spawn``), each running its kernels on ``cores // N``
  threads (1 once there are as many workers as cores, as ``-j 0`` gives), so the cores are not
  oversubscribed. Start-up (imports) is paid once per worker, not once per file.
* ``dask="tcp://host:8786"``: the same jobs submitted to a ``dask.distributed`` scheduler
  (``pip install 'envconv[dask]'``), each on one kernel thread: a Dask worker already runs one
  job per thread. Workers need envconv installed and the files on a shared path; input and
  output paths are made absolute before the jobs leave this machine.

Modes: ``"all"`` redoes everything; ``"skip-existing"`` skips a job whose outputs all exist;
``"update"`` (like ``maketx -u``) redoes a job only when an output is missing or older than
its input.
"""

from __future__ import annotations

import glob
import logging
import os
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from .. import io
from ..errors import EnvconvError, ImageIOError, UsageError
from ..io import FORMATS
from ..io.face_files import face_glob, has_placeholder, literal_path
from ..io.temps import is_temp_name
from ..layouts import get_layout
from .globs import glob_files
from .outputs import REPORT, check_outputs, input_files
from .pipeline import Pipeline, Read, Resample, Write, count_levels, path_variables

__all__ = [
    "Job", "BatchResult", "BatchInterrupted", "MODES", "STATUSES", "expand_inputs", "make_jobs",
    "run_job", "run_batch", "report_data", "report_text", "write_report", "worker_threads",
]  # fmt: skip

log = logging.getLogger(__name__)

MODES = ("all", "skip-existing", "update")
#: A record's status; ``cancelled``: not run (or not finished) because the batch was
#: interrupted.
STATUSES = ("done", "skipped", "failed", "cancelled")
_GLOB_CHARS = set("*?[")


@dataclass(frozen=True)
class Job:
    """One unit of batch work: a pipeline and the input it runs on (None: it reads its own)."""

    input: str | None
    pipeline: Pipeline

    @property
    def name(self) -> str:
        if self.input is not None:
            return self.input
        reads = [s.params["path"] for s in self.pipeline.steps if isinstance(s, Read)]
        return reads[0] if reads else "<pipeline>"


@dataclass
class BatchResult:
    """Records in job order, the wall time of the whole batch in seconds, and what happened
    to the batch itself (``events``: workers that died, an interruption)."""

    records: list[dict[str, Any]]
    seconds: float = 0.0
    counts: dict[str, int] = field(default_factory=dict)
    events: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        # ``cancelled`` is counted only in an interrupted batch.
        counts = {s: sum(r["status"] == s for r in self.records) for s in STATUSES}
        self.counts = {s: n for s, n in counts.items() if n or s != "cancelled"}

    @property
    def ok(self) -> bool:
        return self.counts["failed"] == 0


def expand_inputs(patterns: Iterable[str]) -> list[str]:
    """Absolute, sorted, de-duplicated input files from paths, globs and directories.

    A directory contributes its image files (by extension, not recursive). A glob's ``**``
    follows links to folders but walks each real folder once, never into a cycle
    (:mod:`envconv.engine.globs`). A glob or directory that yields nothing, or a plain path
    that does not exist, is an error before any work.
    envconv's own temporary files (:func:`envconv.io.temps.is_temp_name`) are never inputs.
    """
    found: dict[str, None] = {}
    for pattern in patterns:
        pattern = os.fspath(pattern)
        if os.path.isdir(pattern):
            names = sorted(n for n in os.listdir(pattern)
                           if os.path.splitext(n)[1].lower() in FORMATS and not is_temp_name(n))  # fmt: skip
            matches = [os.path.join(pattern, n) for n in names]
        elif "{face}" in pattern or not (_GLOB_CHARS & set(pattern)):
            if "{face}" not in pattern and not os.path.exists(pattern):
                raise ImageIOError(f"input not found: {pattern}")
            matches = [pattern]
        else:
            matches = [p for p in glob_files(pattern) if not is_temp_name(p)]
        if not matches:
            raise ImageIOError(f"no input files match {pattern}")
        for match in matches:
            found[os.path.abspath(match)] = None
    return list(found)


def make_jobs(
    inputs: Iterable[str | None],
    pipeline: Pipeline,
    no_clobber: bool = False,
    report: str | os.PathLike | None = None,
    also_read: Iterable[str | os.PathLike] = (),
) -> list[Job]:
    """One job per input, with relative write paths made absolute against the current
    directory, every write refusing existing files when ``no_clobber``.

    Raises UsageError, before any work, when an output is an input of the batch (any job's,
    or one of ``also_read``: the graph file; through links too), when two outputs share a
    path (in one job or across jobs), and with ``no_clobber`` when an output exists
    (:mod:`envconv.engine.outputs`). ``report`` (``--report``; ``"-"``: stdout) is one of
    the outputs. Outputs whose path needs a file header (``{size}`` or ``{level}`` without a
    resample size) are checked when their job runs.
    """
    steps = [_absolute_write(s, no_clobber) for s in pipeline.steps]
    rebased = Pipeline(steps, pipeline.variables)
    jobs = [Job(None if i is None else os.path.abspath(i), rebased) for i in inputs]
    outputs, read = [], [os.path.abspath(p) for p in also_read]
    for job in jobs:
        for step in job.pipeline.bound(job.input):
            if isinstance(step, Read):
                read += input_files(step.params["path"], step.params.get("layout"),
                                    step.params.get("faces"))  # fmt: skip
        outputs += [(path, refuse, job.name) for path, refuse in _static_outputs(job)]
    if report is not None and os.fspath(report) != "-":
        outputs.append((os.path.abspath(report), no_clobber, REPORT))
    check_outputs(outputs, read)
    return jobs


def _absolute_write(step, no_clobber: bool):
    if isinstance(step, Write) and (step.params["base"] is None or no_clobber):
        base = step.params["base"] if step.params["base"] is not None else os.getcwd()
        return Write(**{**step.params, "base": base,
                        "no_clobber": step.params["no_clobber"] or no_clobber})  # fmt: skip
    return step


def _static_outputs(job: Job) -> list[tuple[str, bool]]:
    """(path, no_clobber) of the outputs that follow from names alone (those that need a file
    header are left out), previews included."""
    out, resample, variables = [], None, path_variables(job.input)
    for step in job.pipeline.bound(job.input):
        if isinstance(step, Read):
            variables, resample = path_variables(step.params["path"]), None
        elif isinstance(step, Resample):
            resample = step
        elif isinstance(step, Write):
            values = dict(variables)
            if resample is not None:
                values["layout"] = resample.params["to"]
                if resample.params["size"]:
                    values["size"] = resample.params["size"]
            for key in ("path", "preview") if step.params["preview"] else ("path",):
                try:
                    path = step.target(values, key, job.pipeline.variables)
                    files = _named_files(path, resample, step.options.get("faces"), key)
                except EnvconvError:
                    continue
                out += [(f, step.params["no_clobber"]) for f in files]
    return out


def _named_files(path: str, resample: Resample | None, faces, key: str = "path") -> list[str]:
    """The final files of one write path when they follow from its name and the resample
    before it (a ``{level}`` count needs the size; without it, a file header)."""
    if key == "preview" or not (has_placeholder(path, "level") or has_placeholder(path, "face")):
        return [literal_path(path)]
    if resample is None:
        return []
    levels = 1
    if has_placeholder(path, "level"):
        size, guard = resample.params["size"], resample.params["guard"]
        if not size:
            return []
        layout = get_layout(resample.params["to"])
        width, height = layout.file_size(int(size), 0 if guard == "fill" else int(guard))
        levels = count_levels(width, height, resample.params["mips"])
    return io.output_paths(resample.params["to"], path, levels, faces=faces)


def worker_threads(jobs: int, cores: int | None = None) -> int:
    """Kernel threads per worker so that ``jobs`` workers share the cores."""
    if cores is None:
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return max(1, (cores or 1) // max(1, jobs))


def _init_worker(threads: int, capture: bool = False) -> None:
    """A worker process of this batch: its share of the cores, and the capture of library
    output when the command line that started it captures (:mod:`envconv.io.chatter`)."""
    from ..io.chatter import capture_descriptors
    from ..io.files import limit_threads
    from ..resample.kernels import set_threads

    limit_threads(threads)
    set_threads(threads)
    capture_descriptors(capture)


def _run_job_on_dask_worker(job: Job, mode: str = "all") -> dict[str, Any]:
    """:func:`run_job` on one kernel thread: the Dask worker runs one job per thread, and
    its other threads keep their own count (a per-call count, not the process's)."""
    from ..resample.kernels import threads_for

    with threads_for(1):
        return run_job(job, mode)


def _input_mtime(job: Job) -> float:
    times = []
    for step in job.pipeline.bound(job.input):
        if isinstance(step, Read) and step.params["path"]:
            for path in glob.glob(face_glob(step.params["path"])):
                times.append(os.path.getmtime(path))
    return max(times) if times else float("inf")


def _up_to_date(job: Job, files: list[str], mode: str) -> bool:
    if not files or not all(os.path.exists(f) for f in files):
        return False
    if mode == "skip-existing":
        return True
    return min(os.path.getmtime(f) for f in files) >= _input_mtime(job)


def run_job(job: Job, mode: str = "all") -> dict[str, Any]:
    """Run one job and return its record (:func:`envconv.engine.records.run_record`); never
    raises for a bad input."""
    from .records import run_record

    start = time.perf_counter()
    written: list[str] = []
    timings: dict[str, float] = {}
    outputs, status, error = [], "done", None
    try:
        if mode != "all":
            files = job.pipeline.output_files(job.input)
            if _up_to_date(job, files, mode):
                status, written = "skipped", files
        if status == "done":
            outputs = job.pipeline.run(job.input, keep=False, written=written, timings=timings)
    except EnvconvError as exc:
        status, error = "failed", str(exc)
    except Exception as exc:  # a batch reports every failure and goes on
        log.debug("job %s failed", job.name, exc_info=True)
        status, error = "failed", f"internal error: {type(exc).__name__}: {exc}"
    return run_record(job.name, written, outputs, time.perf_counter() - start, timings, status,
                      error)  # fmt: skip


def _failed(job: Job, exc: BaseException | str, status: str = "failed") -> dict[str, Any]:
    from .records import run_record

    error = exc if isinstance(exc, str) else f"{type(exc).__name__}: {exc}"
    return run_record(job.name, [], [], 0.0, {}, status, error)


class BatchInterrupted(KeyboardInterrupt):
    """A batch stopped by SIGINT/SIGTERM; ``result`` holds what finished (the rest
    ``cancelled``) and ``cause`` the interruption, whose ``signum`` it carries."""

    def __init__(self, result: BatchResult, cause: BaseException) -> None:
        super().__init__(*cause.args)
        self.result, self.cause = result, cause
        self.signum = getattr(cause, "signum", 2)


def run_batch(
    jobs: list[Job],
    workers: int = 1,
    mode: str = "all",
    dask: str | None = None,
    on_record: Callable[[dict[str, Any]], None] | None = None,
) -> BatchResult:
    """Run ``jobs``; call ``on_record`` as each finishes; return records in job order.

    Parameters
    ----------
    workers : int
        Processes on this machine (``-j``); 1 runs in this process. A worker that dies costs
        only its own job, which runs once more on a fresh worker (:mod:`envconv.engine.workers`).
    mode : {"all", "skip-existing", "update"}
    dask : str, optional
        Address of a Dask scheduler; the jobs then run there and ``workers`` is ignored.

    Raises
    ------
    BatchInterrupted
        On SIGINT/SIGTERM (KeyboardInterrupt): no further job starts, and the exception
        carries the records of what finished, the rest ``cancelled``.
    """
    if mode not in MODES:
        raise UsageError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    start = time.perf_counter()
    records: list[dict[str, Any] | None] = [None] * len(jobs)

    def finish(index: int, record: dict[str, Any]) -> None:
        records[index] = record
        if on_record is not None:
            on_record(record)

    events: list[str] = []
    try:
        if dask:
            _run_dask(dask, jobs, mode, finish)
        elif workers <= 1 or len(jobs) <= 1:
            for index, job in enumerate(jobs):
                finish(index, run_job(job, mode))
        else:
            events = _run_processes(jobs, min(workers, len(jobs)), mode, finish)
    except KeyboardInterrupt as exc:  # SIGINT/SIGTERM: report what finished
        from .interrupt import describe

        done = [r if r is not None else _failed(j, describe(exc), "cancelled")
                for r, j in zip(records, jobs, strict=True)]  # fmt: skip
        result = BatchResult(done, round(time.perf_counter() - start, 4))
        result.events.append(f"{describe(exc)}: {result.counts.get('cancelled', 0)} jobs cancelled")
        raise BatchInterrupted(result, exc) from None
    done = [
        r if r is not None else _failed(j, RuntimeError("not run"))
        for r, j in zip(records, jobs, strict=True)
    ]
    return BatchResult(done, round(time.perf_counter() - start, 4), events=events)


def _run_processes(jobs: list[Job], workers: int, mode: str, finish) -> list[str]:
    from functools import partial

    from ..io.chatter import capturing
    from .workers import run_pool

    return run_pool(jobs, workers, finish, call=partial(run_job, mode=mode),
                    init=partial(_init_worker, worker_threads(workers), capturing()),
                    failed=_failed, outputs=_output_files)  # fmt: skip


def _output_files(job: Job) -> list[str]:
    """The output paths of a job that follow from names alone (see :func:`_static_outputs`)."""
    return [path for path, _ in _static_outputs(job)]


def _run_dask(address: str, jobs: list[Job], mode: str, finish) -> None:
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise UsageError("--dask needs dask.distributed; install it with "
                         "pip install 'envconv[dask]'") from None  # fmt: skip
    try:
        client = Client(address)  # connect timeout: distributed.comm.timeouts.connect
    except (OSError, TimeoutError, ValueError) as exc:
        raise EnvconvError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    with client:
        futures = client.map(_run_job_on_dask_worker, jobs, mode=mode, pure=False)
        index = {future.key: i for i, future in enumerate(futures)}
        try:
            for future in as_completed(futures):
                i = index[future.key]
                try:
                    finish(i, future.result())
                except Exception as exc:  # a worker died
                    finish(i, _failed(jobs[i], exc))
        except KeyboardInterrupt:
            client.cancel(futures)
            raise


def report_data(result: BatchResult) -> dict[str, Any]:
    """The ``--report`` JSON: a summary and one record per input, in input order."""
    from .. import __version__

    return {
        "envconv": __version__,
        "summary": {**result.counts, "total": len(result.records), "seconds": result.seconds},
        "events": result.events,
        "files": result.records,
    }


def report_text(result: BatchResult) -> str:
    """:func:`report_data` as JSON text (what ``--report`` writes, ``--report -`` prints)."""
    import json

    return json.dumps(report_data(result), indent=2) + "\n"


def write_report(path: str | os.PathLike, result: BatchResult) -> None:
    """Write :func:`report_text` to ``path`` through a temporary file and a rename, making
    its folder if missing (:func:`make_jobs` checked the path against the output policy)."""
    from ..io import write_bytes

    path = os.fspath(path)
    try:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        write_bytes(report_text(result).encode("utf-8"), path)
    except ImageIOError as exc:
        raise ImageIOError(f"report: {exc}") from None
    except OSError as exc:
        raise ImageIOError(f"report: cannot write {path}: {exc.strerror or exc}") from None
