"""The engine: one walker for every entry point.

* :mod:`~envconv.engine.steps`: the steps (Read, Rotate, Exposure, Colorspace, Resample, Write);
* :mod:`~envconv.engine.pipeline`: a list of steps as a library object (``Pipeline``);
* :mod:`~envconv.engine.walk`: the one walker that checks, plans and runs a pipeline;
* :mod:`~envconv.engine.api`: ``convert_file`` and friends, the command line's library calls;
* :mod:`~envconv.engine.graph`: TOML graph files into pipelines;
* :mod:`~envconv.engine.batch`, :mod:`~envconv.engine.workers`: many inputs, local processes
  or Dask; :mod:`~envconv.engine.globs`: their input globs (``**`` never into a link cycle);
* :mod:`~envconv.engine.outputs`: the output policy (never onto an input, never twice, ``-n``);
* :mod:`~envconv.engine.memory`: the memory estimate and guard;
* :mod:`~envconv.engine.interrupt`: SIGINT and SIGTERM end a run cleanly.

The package imports nothing itself: a submodule loads on first use.
"""

from ..lazy import package_getattr

__all__: list[str] = []

__getattr__ = package_getattr(__name__)
