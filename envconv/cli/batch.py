"""``envconv batch INPUTS... --out TEMPLATE [STEPS...]``: one recipe over many files.

The steps that follow ``batch`` in the chain are the per-file recipe (a leading ``read`` takes
no INPUT). ``--out`` supplies the write after every resample when the recipe has no ``write``.
The batch options are shared with ``envconv run``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import click

from ..engine.batch import BatchInterrupted, expand_inputs, make_jobs, run_batch, write_report
from ..engine.graph import load_graph
from ..engine.pipeline import Pipeline, Resample, Write
from .main import cli
from .messages import echo_result
from .options import echo_document, json_option, no_clobber_option
from .progress import Progress, summary_line

__all__ = ["batch_command", "batch_options", "BatchSpec", "run_batch_command", "execute"]

BATCH_OPTIONS = [
    click.option("-j", "--jobs", "workers", type=click.IntRange(min=0), default=1, show_default=True, help="Worker processes (0: one per core); kernel threads are split between them."),
    click.option("--skip-existing", is_flag=True, help="Skip an input whose outputs all exist."),
    click.option("-u", "--update", is_flag=True, help="Redo an input only when an output is missing or older than it."),
    click.option("--report", "report", metavar="FILE.json", help="Write one JSON record per input (status, outputs, seconds, error); '-' prints it on stdout (the summary then goes to stderr)."),
    click.option("--dask", "dask", metavar="SCHEDULER", help="Run the jobs on a Dask cluster (tcp://host:8786); needs envconv[dask]."),
    click.option("--dry-run", is_flag=True, help="Print every output (layout, size, levels, files) without reading pixels."),
    json_option,
    no_clobber_option,
]  # fmt: skip


def batch_options(fn):
    for decorator in reversed(BATCH_OPTIONS):
        fn = decorator(fn)
    return fn


@dataclass
class BatchSpec:
    """What ``batch`` was given; the steps after it arrive in the result callback."""

    inputs: tuple[str, ...]
    out: str | None
    graph: str | None
    options: dict[str, Any] = field(default_factory=dict)


@cli.command("batch")
@click.argument("inputs", nargs=-1, metavar="INPUTS...")
@click.option(
    "-o",
    "--out",
    metavar="TEMPLATE",
    help="Output path, e.g. 'out/{stem}_{layout}.exr'; written after every resample.",
)
@click.option(
    "--graph",
    metavar="FILE",
    help="Take the recipe (and, without INPUTS, the inputs) from a graph file.",
)
@batch_options
def batch_command(inputs, out, graph, **options):
    """Run the steps that follow on every input (files, globs or directories).

    A bad file never stops the batch; the exit status is 1 if any input failed. Before any
    work the batch is refused if an output is one of its inputs (also through a link, e.g.
    --out '{dir}/{stem}.exr'), if two outputs share a path, and with -n if an output exists.
    A worker that dies costs only its own job, run once more on a fresh worker. SIGINT/SIGTERM
    cancel the queued jobs, write the report of what finished and exit 130/143.

    \b
    Example:
      envconv batch 'hdri/*.exr' --out 'out/{stem}_{layout}.exr' -j 2 \\
              resample --to cube-vcross --size 512 resample --to paraboloid --size 256
    """
    return BatchSpec(tuple(inputs), out, graph, options)


def _with_out(steps: list, out: str | None) -> list:
    if out is None:
        return steps
    if any(isinstance(s, Write) for s in steps):
        raise click.UsageError("give either --out or write steps, not both")
    result = []
    for step in steps:
        result.append(step)
        if isinstance(step, Resample):
            result.append(Write(out))
    if not any(isinstance(s, Resample) for s in steps):
        result.append(Write(out))
    return result


def run_batch_command(spec: BatchSpec, steps: list) -> None:
    """Build the jobs of a ``batch`` chain and run them."""
    if spec.graph:
        if steps:
            raise click.UsageError("give either --graph or steps after batch, not both")
        graph = load_graph(spec.graph, recipe=bool(spec.inputs) or None)
        steps, variables = graph.steps, graph.variables
        patterns = list(spec.inputs) or graph.inputs
    else:
        variables, patterns = {}, list(spec.inputs)
    if not patterns:
        raise click.UsageError("batch needs INPUTS: files, globs or directories")
    steps = _with_out(list(steps), spec.out)
    if not any(isinstance(s, Write) for s in steps):
        raise click.UsageError("nothing would be written: give --out or a write step")
    pipeline = Pipeline(steps, variables)
    pipeline.validate(input="input.exr", require_writes=True)
    options = dict(spec.options)
    jobs = make_jobs(expand_inputs(patterns), pipeline, options.pop("no_clobber", False),
                     options["report"], [spec.graph] if spec.graph else [])  # fmt: skip
    execute(jobs, **options)


def execute(jobs, workers=1, skip_existing=False, update=False, report=None, dask=None,
            dry_run=False, as_json=False, command="batch") -> None:  # fmt: skip
    """Run (or with ``dry_run`` plan) ``jobs`` with progress, summary and report; with
    ``as_json`` the summary is one JSON document of ``command`` on stdout."""
    if skip_existing and update:
        raise click.UsageError("--skip-existing and --update exclude each other")
    if report == "-" and as_json:
        raise click.UsageError("--report - and --json both print on stdout; give one of them")
    if dry_run:
        _print_plan(jobs, command if as_json else None)
        return
    if workers == 0:
        from ..engine.batch import worker_threads

        workers = worker_threads(1)
    mode = "skip-existing" if skip_existing else "update" if update else "all"
    progress = Progress(len(jobs))
    try:
        result = run_batch(jobs, workers=workers, mode=mode, dask=dask, on_record=progress.update)
    except BatchInterrupted as exc:  # the report of what finished, then exit 130/143
        if report:
            _report(report, exc.result)
        raise
    finally:
        progress.close()
    if report:
        _report(report, result)
    if as_json:
        echo_document(command, result.records, result.seconds, result.events)
    elif report == "-":  # stdout holds the report alone: the summary goes to stderr
        click.echo(summary_line(result.counts, result.seconds, len(jobs)), err=True)
    else:
        echo_result(summary_line(result.counts, result.seconds, len(jobs)))
    if not result.ok:
        raise click.exceptions.Exit(1)


def _report(path: str, result) -> None:
    """Write the report to ``path``, or print it on stdout for ``-``."""
    if path == "-":
        from ..engine.batch import report_text

        echo_result(report_text(result).rstrip("\n"))
    else:
        write_report(path, result)


def _print_plan(jobs, json_command: str | None = None) -> None:
    """Each job's planned outputs (:func:`envconv.engine.records.plan_job`) as text, or as the
    JSON document of ``json_command``; exit 1 when a job cannot be planned."""
    import time

    from ..engine.records import plan_job

    start, records = time.perf_counter(), []
    for job in jobs:
        record = plan_job(job)
        records.append(record)
        if json_command is None:
            _echo_planned(record)
    if json_command is not None:
        echo_document(json_command, records, time.perf_counter() - start, dry_run=True)
    if any(record["error"] for record in records):
        raise click.exceptions.Exit(1)


def _echo_planned(record) -> None:
    echo_result(record["input"])
    if record["error"]:
        echo_result(f"  error: {record['error']}")
    for o in record["maps"]:
        levels = f"{o['levels']} level{'s' if o['levels'] > 1 else ''}"
        echo_result(f"  {o['layout']}  N={o['size']}  G={o['guard']}  {o['width']}x{o['height']}  "
                   f"{levels}")  # fmt: skip
        for entry in o["files"]:
            echo_result(f"    {entry['path']}")
