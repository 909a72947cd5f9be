"""Plain records of what a run wrote or a plan would write, for JSON: ``--json`` on convert, run
and batch, and the batch report (``--report``).

One document describes any run (``docs/shell.md``, "JSON output"): the envconv version, the
command, whether it was a dry run, a summary, the batch's events and one record per input;
each record lists its output maps and each map its files. Paths are as the run wrote them;
sizes are pixels, ``bytes`` the size of each file on disk (None in a dry run), and seconds
wall-clock seconds.
"""

from __future__ import annotations

import os
from typing import Any

from .steps import Output

__all__ = ["map_record", "run_record", "plan_record", "plan_job", "document", "PLANNED"]

#: The status of a dry run's record whose outputs were planned.
PLANNED = "planned"


def map_record(output: Output, planned: bool = False) -> dict[str, Any]:
    """One output map: layout, N, guard, one file's width × height, MIP levels, channels, the
    seconds its resample and writes took, and every file with what the writer stores in it
    (format, bit depth, compression, colour space, channels, levels) and, after a run, its
    size in bytes. A preview picture is listed with ``"preview": true``."""
    stored = {path: plan for plan in output.writes for path in plan.files}
    files = []
    for path in output.files:
        plan = stored.get(path)
        entry: dict[str, Any] = {"path": path, "bytes": None if planned else _bytes(path)}
        if plan is None:
            entry["preview"] = True
        else:
            entry.update(format=plan.format, bit_depth=plan.pixel_type,
                         compression=plan.compression, colorspace=plan.colorspace,
                         channels=list(plan.channels), levels=plan.levels)  # fmt: skip
        files.append(entry)
    return {
        "layout": output.layout, "size": output.size, "guard": output.guard,
        "width": output.width, "height": output.height, "levels": output.levels,
        "channels": list(output.channels),
        "seconds": {k: round(v, 4) for k, v in output.seconds.items()}, "files": files,
    }  # fmt: skip


def _bytes(path: str) -> int | None:
    try:
        return os.path.getsize(path)
    except OSError:
        return None


def run_record(input: str, written: list[str], outputs: list[Output], seconds: float,
               timings: dict[str, float], status: str = "done",
               error: str | None = None) -> dict[str, Any]:  # fmt: skip
    """The record of one input of a run (one job of a batch, or ``convert``): ``input``,
    ``status`` (``done``, ``skipped``, ``failed``, ``cancelled``), ``outputs`` (every file
    written, or found up to date), ``seconds``, ``error`` (one line, or None), ``timings``
    (seconds reading, resampling and writing) and ``maps`` (:func:`map_record` of each
    output written)."""
    return {
        "input": input, "status": status, "outputs": list(written),
        "seconds": round(seconds, 4), "error": error,
        "timings": {k: round(v, 4) for k, v in timings.items()},
        "maps": [map_record(o) for o in outputs if o.files],
    }  # fmt: skip


def plan_record(input: str, outputs: list[Output] | None, error: str | None = None,
                seconds: float = 0.0) -> dict[str, Any]:  # fmt: skip
    """The record of one input of a dry run: what would be written (status ``planned``), or
    why it cannot be planned (status ``failed``)."""
    maps = [map_record(o, planned=True) for o in outputs or []]
    return {
        "input": input, "status": PLANNED if error is None else "failed",
        "outputs": [f["path"] for m in maps for f in m["files"]], "seconds": round(seconds, 4),
        "error": error, "timings": {}, "maps": maps,
    }  # fmt: skip


def plan_job(job) -> dict[str, Any]:
    """:func:`plan_record` of a batch job (:class:`envconv.engine.batch.Job`): its pipeline
    planned from headers; an error is the record's, as in a real batch."""
    import logging
    import time

    from ..errors import EnvconvError

    start = time.perf_counter()
    try:
        outputs = job.pipeline.plan(job.input)
    except EnvconvError as exc:
        return plan_record(job.name, None, str(exc), time.perf_counter() - start)
    except Exception as exc:  # reported and the plan goes on, like a real batch
        logging.getLogger(__name__).debug("planning %s failed", job.name, exc_info=True)
        error = f"internal error: {type(exc).__name__}: {exc}"
        return plan_record(job.name, None, error, time.perf_counter() - start)
    return plan_record(job.name, outputs, seconds=time.perf_counter() - start)


def document(command: str, records: list[dict[str, Any]], seconds: float,
             events: list[str] | None = None, dry_run: bool = False) -> dict[str, Any]:  # fmt: skip
    """The JSON document of a run of ``command`` (``convert``, ``run`` or ``batch``): the
    records in input order, with a summary that counts them by status (``done``, ``skipped``
    and ``failed`` always, or ``planned`` and ``failed`` for a dry run; ``cancelled`` when an
    interrupted batch has some), their total and the wall-clock seconds."""
    from .. import __version__

    counts = dict.fromkeys((PLANNED, "failed") if dry_run else ("done", "skipped", "failed"), 0)
    for record in records:
        counts[record["status"]] = counts.get(record["status"], 0) + 1
    return {
        "envconv": __version__, "command": command, "dry_run": dry_run,
        "summary": {**counts, "total": len(records), "seconds": round(seconds, 4)},
        "events": list(events or []), "files": records,
    }  # fmt: skip
