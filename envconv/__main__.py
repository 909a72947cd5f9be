"""``envconv`` as a program: the console script and ``python -m envconv``.

The console script imports this module, not :mod:`envconv.cli`, so that SIGINT and SIGTERM
are in envconv's hands (:mod:`envconv.engine.interrupt`) before click, numpy and the commands
load, which takes tens of milliseconds: a Ctrl-C at any moment from here on ends the run with
one line and status 130 (143 for SIGTERM), never a ``KeyboardInterrupt`` traceback. Until the
handlers are installed, a signal is only recorded, then raised by them.

A signal that lands while Python itself starts (its ``site`` module, the first few
milliseconds, before any envconv code runs) is Python's to report: it prints "Fatal Python
error: init_import_site" and exits 1, whatever the program.
"""

from __future__ import annotations

import signal
import sys

__all__ = ["main"]


def main() -> None:
    """Run the ``envconv`` command line (:func:`envconv.cli.main.main`)."""
    pending: list[int] = []

    def record(signum, frame) -> None:
        pending.append(signum)

    previous = {s: signal.signal(s, record) for s in (signal.SIGINT, signal.SIGTERM)}
    from .engine.interrupt import install, report

    try:
        install()
        for signum in pending[:1]:
            if previous.get(signum) is not signal.SIG_IGN:
                signal.raise_signal(signum)  # now raised as envconv.engine.interrupt's
        from .cli.main import main as command_line

        command_line()
    except KeyboardInterrupt as exc:  # a signal before the command line took over
        sys.exit(report(exc))


if __name__ == "__main__":  # pragma: no cover
    main()
