"""``envconv run GRAPH``: run a graph file (TOML or JSON), or print its plan."""

from __future__ import annotations

import click

from ..engine.batch import expand_inputs, make_jobs
from ..engine.graph import load_graph
from .batch import batch_options, execute
from .main import cli

__all__ = ["run_command"]


@cli.command("run")
@click.argument("graph_path", metavar="GRAPH")
@batch_options
def run_command(graph_path, **options):
    """Run the pipeline in GRAPH (see docs/pipeline-file.md), once per input it lists.

    The file is validated before any work; --dry-run prints every output (layout, size,
    levels and files) from the inputs' headers, without reading pixels. Also before any work,
    the run is refused if an output is an input (also through a link), if two outputs share a
    path, and with -n if an output exists.

    \b
    Example:
      envconv run examples/graph.toml --dry-run
      envconv run examples/graph.toml --json > run.json
    """
    graph = load_graph(graph_path)
    inputs = expand_inputs(graph.inputs) if graph.inputs else [None]
    jobs = make_jobs(inputs, graph.pipeline, options.pop("no_clobber"), options["report"],
                     [graph_path])  # fmt: skip
    execute(jobs, **options, command="run")
