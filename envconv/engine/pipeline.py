"""Pipelines: a list of steps that reads one source and writes any number of outputs.

A pipeline is what ``envconv convert`` runs (Read → Resample → Write), what
``envconv read … resample … write …`` runs at the shell, what a graph file describes
(:mod:`envconv.engine.graph`) and what ``envconv batch`` runs once per input: one engine, one walker
(:mod:`envconv.engine.walk`) that checks, plans and runs. The steps (:mod:`envconv.engine.steps`) are plain
objects a Python user builds without click:

>>> from envconv.engine.pipeline import Pipeline, Read, Resample, Write
>>> Pipeline([
...     Read("sky.exr"),
...     Resample("cube-vcross", size=512), Write("cross.exr"),
...     Resample("paraboloid", size=256, alpha=True, guard=2), Write("para.exr"),
... ]).run()                                                   # doctest: +SKIP

The rules
---------
* ``Read`` sets the *source*: the file read, converted to the working space, then prepared
  (NaN/Inf, exposure, negatives: :func:`envconv.color.prepare.prepare_input`).
* Every ``Resample`` starts from the source as it stands, never from another output, so each
  output is resampled exactly once. Rotations are not applied to pixels at all: they are
  composed and handed to the next resample, so rotating costs no extra filtering.
* ``Write`` writes the *latest output*: that of the last ``Resample``, or the source itself when
  no ``Resample`` has run since the ``Read`` (a format change; a pending rotation then resamples
  into the source's own layout).
* ``Exposure`` and ``Colorspace`` between a ``Resample`` and its first ``Write`` change that
  output only (e.g. an sRGB preview next to a linear master). Anywhere else (after a ``Read``
  or after a ``Write``) they change the source *and* the latest output: a later ``Write``
  without a ``Resample`` writes the latest output changed, and later resamples see the change.
* ``Rotate`` between a ``Resample`` and its first ``Write`` is an error (the output would be
  resampled twice); after a written output it turns the source for later resamples, and a
  ``Write`` before the next ``Resample`` is an error (it would write the unturned output).
* After a ``Colorspace`` step a ``Write`` keeps that colour space and tags the file with it,
  unless the write names its own ``output_colorspace``; otherwise outputs are written in the
  default space of their format (see :mod:`envconv.io.encode`).

The output policy (:mod:`envconv.engine.outputs`) is checked on the whole plan before any pixel is
read: no output onto an input, no two outputs on one path, and with ``no_clobber`` no output
that exists. ``Write`` paths take variables: ``{stem}``, ``{name}``, ``{ext}`` (no dot) and
``{dir}`` of the input last read, ``{layout}`` and ``{size}`` (N) of what is written, and user
variables (which may use each other, but not in a cycle). ``{face}`` and ``{level}`` are left
for :func:`envconv.io.write`.
"""

from __future__ import annotations

import logging
import os
from typing import Any

from ..errors import UsageError
from .outputs import check_outputs, input_files
from .steps import (
    VARIABLES,
    Colorspace,
    Exposure,
    Output,
    Read,
    Resample,
    Rotate,
    Step,
    Write,
    check_variables,
    compose_rotations,
    count_levels,
    expand_path,
    path_variables,
)  # fmt: skip
from .walk import Walk

__all__ = [
    "Step", "Read", "Rotate", "Exposure", "Colorspace", "Resample", "Write",
    "Pipeline", "Output", "expand_path", "path_variables", "compose_rotations", "count_levels",
    "VARIABLES",
]  # fmt: skip

log = logging.getLogger(__name__)


class Pipeline:
    """An ordered list of steps, run with the rules of this module.

    Parameters
    ----------
    steps : sequence of Step
        The steps. A recipe for many inputs starts without a ``Read`` (or with ``Read()``), and
        gets its input from ``run(input=...)``.
    variables : dict, optional
        User variables for ``Write`` paths, e.g. ``{"out": "build"}`` for ``{out}/{stem}.exr``.
    """

    def __init__(self, steps, variables: dict[str, Any] | None = None) -> None:
        self.steps = tuple(steps)
        self.variables = check_variables(dict(variables or {}))
        for index, step in enumerate(self.steps, 1):
            if not isinstance(step, Step):
                raise UsageError(f"step {index}: expected a pipeline step, got {step!r}")

    def __repr__(self) -> str:
        return f"Pipeline({list(self.steps)!r})"

    def bound(self, input: str | os.PathLike | None = None) -> list[Step]:
        """The steps with ``input`` as the source of a recipe (a leading or path-less Read)."""
        steps = list(self.steps)
        if input is not None:
            if not steps or not isinstance(steps[0], Read):
                steps.insert(0, Read())
            steps = [Read(input, **s.options) if isinstance(s, Read) and s.params["path"] is None
                     else s for s in steps]  # fmt: skip
        return steps

    def validate(self, input=None, require_writes: bool = False) -> None:
        """Check the order of the steps and the ``Write`` paths, without touching any file.

        Raises UsageError naming the step (1-based) and the problem.
        """
        steps = self.bound(input) if input is not None else list(self.steps)
        Walk(self.variables, "check").walk(steps, require_writes)

    def run(self, input=None, keep: bool = True, written: list[str] | None = None,
            warnings: list[str] | None = None,
            timings: dict[str, float] | None = None) -> list[Output]:  # fmt: skip
        """Run the pipeline; return one :class:`Output` per resample (or plain write).

        The whole run is planned first (headers only) and the output policy checked
        (:mod:`envconv.engine.outputs`). ``written``, when given, collects each file as soon as it is
        written, so a caller still knows what was written if a later step fails. ``warnings``,
        when a list, collects one-line warnings (NaN/Inf in an input, clipping), else they are
        logged at WARNING level. ``timings``, when a dict, adds up the seconds spent in
        ``read`` (with preparing the source), ``resample`` and ``write``.
        """
        steps = self.bound(input)
        self._plan(steps)
        walk = Walk(self.variables, "run", keep=keep, written=written, warnings=warnings,
                    timings=timings)  # fmt: skip
        return walk.walk(steps)

    def plan(self, input=None) -> list[Output]:
        """What ``run`` would write (layouts, sizes, levels, files), reading headers only.

        Refuses, like ``run``, what breaks the output policy.
        """
        return [o for o in self._plan(self.bound(input)) if o.files]

    def _plan(self, steps: list[Step]) -> list[Output]:
        Walk(self.variables, "check").walk(steps)
        walk = Walk(self.variables, "plan")
        outputs = walk.walk(steps)
        inputs = [f for s in steps if isinstance(s, Read)
                  for f in input_files(s.params["path"], s.params.get("layout"),
                                       s.params.get("faces"))]  # fmt: skip
        check_outputs(walk.targets, inputs)
        return outputs

    def output_files(self, input=None) -> list[str]:
        """Every file ``run`` would write (reads headers only)."""
        return [f for output in self.plan(input) for f in output.files]
