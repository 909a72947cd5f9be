"""What the ``envconv`` group does with the steps its chained commands return.

The group (:mod:`envconv.cli.main`) only collects; this module, imported with
:mod:`envconv.cli`, registers the result callback that validates and runs a chain, or, after
``batch``, runs it once per input. Keeping it out of :mod:`envconv.cli.main` means the commands
import the group and the group imports none of them.
"""

from __future__ import annotations

import click

from .main import cli
from .messages import echo_result

__all__ = ["compose_steps", "run_chain"]


@cli.result_callback()
def compose_steps(results, **_global_options) -> None:
    """Run the steps of a chain (standalone commands return None and have already run)."""
    steps = [r for r in results if r is not None]
    if steps:
        run_chain(steps)


def run_chain(steps: list) -> None:
    """Validate and run a chain of steps; a leading batch spec runs them per input.

    The whole chain is checked, then planned from headers and the output policy applied
    (:mod:`envconv.engine.outputs`), before any pixel is read.
    """
    from ..engine.pipeline import Pipeline
    from .batch import BatchSpec, run_batch_command

    if isinstance(steps[0], BatchSpec):
        if any(isinstance(s, BatchSpec) for s in steps[1:]):
            raise click.UsageError("batch can appear only once, at the start of the chain")
        run_batch_command(steps[0], steps[1:])
        return
    if any(isinstance(s, BatchSpec) for s in steps):
        raise click.UsageError("batch must come first: envconv batch INPUTS... STEPS...")
    pipeline = Pipeline(steps)
    pipeline.validate(require_writes=True)
    for output in pipeline.run(keep=False):
        for path in output.files:
            echo_result(path)
