"""``envconv`` as a program: the console script and ``python -m envconv``.

The console script imports this module, not :mod:`envconv.cli`, so that SIGINT and SIGTERM
are in envconv's hands before click, numpy and the commands load, which takes tens of
milliseconds: a Ctrl-C at any moment from here on ends the run with one line and status 130
(143 for SIGTERM), never a ``KeyboardInterrupt`` traceback. Importing this module records
the two signals at once (through ``_signal``, the C half of :mod:`signal`, which loads in
microseconds where :mod:`signal` takes milliseconds to build its enums); :func:`main` hands
them to :mod:`envconv.engine.interrupt` and raises any that came meanwhile. So this module is
the program only: a library never imports it.

A signal that lands while Python itself starts (its ``site`` module) or loads the package's
``__init__``, the first few milliseconds, comes before any of this and is Python's to report.
"""

from __future__ import annotations

import _signal
import sys

__all__ = ["main"]

_pending: list[int] = []


def _record(signum, frame) -> None:
    _pending.append(signum)


_previous = {s: _signal.signal(s, _record) for s in (_signal.SIGINT, _signal.SIGTERM)}


def main() -> None:
    """Run the ``envconv`` command line (:func:`envconv.cli.main.main`)."""
    from .engine.interrupt import install, report

    try:
        install()
        for signum in _pending[:1]:
            if _previous.get(signum) != _signal.SIG_IGN:
                _signal.raise_signal(signum)  # now raised as envconv.engine.interrupt's
        from .cli.main import main as command_line

        command_line()
    except KeyboardInterrupt as exc:  # a signal before the command line took over
        sys.exit(report(exc))


if __name__ == "__main__":  # pragma: no cover
    main()
