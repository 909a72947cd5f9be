"""Progress on stderr: a batch's bar with ETA (plain log lines off a terminal), and a single
conversion's resampling line on a terminal once it has run for 2 s."""

from __future__ import annotations

import sys
import time
from typing import Any

import click

__all__ = ["Progress", "ResampleProgress", "format_seconds", "summary_line"]


def format_seconds(seconds: float) -> str:
    """``1:02:03``, ``2:03`` or ``4.2 s``."""
    if seconds < 60:
        return f"{seconds:.1f} s"
    minutes, secs = divmod(int(round(seconds)), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def summary_line(counts: dict[str, int], seconds: float, total: int) -> str:
    """``20 files: 18 done, 0 skipped, 2 failed in 3.1 s (0.17 s per file)``."""
    per = f" ({seconds / total:.3f} s per file)" if total else ""
    return (f"{total} files: {counts['done']} done, {counts['skipped']} skipped, "
            f"{counts['failed']} failed in {format_seconds(seconds)}{per}")  # fmt: skip


def _isatty() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class Progress:
    """Shows each finished record: ``update(record)`` as jobs finish, ``close()`` at the end.

    On a terminal one line is redrawn with ``\\r``: a bar, the counts and the ETA (from the mean
    time per finished file). Otherwise each file gets one plain line. Failures always get their
    own line with the error.
    """

    def __init__(self, total: int, tty: bool | None = None, width: int = 24) -> None:
        self.total, self.width = total, width
        self.tty = _isatty() if tty is None else tty
        self.counts = {"done": 0, "skipped": 0, "failed": 0}
        self.start = time.perf_counter()
        self._drawn = False

    @property
    def finished(self) -> int:
        return sum(self.counts.values())

    def update(self, record: dict[str, Any]) -> None:
        self.counts[record["status"]] += 1
        line = (f"[{self.finished:>{len(str(self.total))}}/{self.total}] {record['status']:<7} "
                f"{record['input']} ({record['seconds']:.2f} s)")  # fmt: skip
        if record["status"] == "failed":
            line += f": {record['error']}"
        if self.tty:
            if record["status"] == "failed":
                self._clear()
                click.echo(f"envconv: {line}", err=True)
            self._draw()
        else:
            click.echo(f"envconv: {line}", err=True)

    def eta(self) -> float | None:
        if not self.finished:
            return None
        elapsed = time.perf_counter() - self.start
        return elapsed / self.finished * (self.total - self.finished)

    def _draw(self) -> None:
        filled = int(self.width * self.finished / max(self.total, 1))
        bar = "#" * filled + "-" * (self.width - filled)
        eta = self.eta()
        c = self.counts
        text = (f"\r[{bar}] {self.finished}/{self.total}  done {c['done']}  skipped "
                f"{c['skipped']}  failed {c['failed']}  ETA {format_seconds(eta or 0.0)} ")  # fmt: skip
        click.echo(text, nl=False, err=True)
        self._drawn = True

    def _clear(self) -> None:
        if self._drawn:
            click.echo("\r\x1b[K", nl=False, err=True)

    def close(self) -> None:
        if self.tty and self._drawn:
            click.echo("", err=True)


class ResampleProgress:
    """A context manager that draws ``envconv: resampling 45%`` on a terminal while a long
    conversion resamples: only on a terminal (a pipe or a log stays quiet), only once the
    command has run for ``delay`` seconds, redrawn in place and erased at the end.

    It watches the kernels' progress counter (:func:`envconv.resample.kernels.watch_progress`).
    """

    def __init__(self, delay: float = 2.0, tty: bool | None = None) -> None:
        self.delay = delay
        self.tty = _isatty() if tty is None else tty
        self.start = time.perf_counter()
        self._drawn = False
        self._previous = None

    def __enter__(self) -> ResampleProgress:
        if self.tty:
            from ..resample.kernels import watch_progress

            self._previous = watch_progress(self.update)
        return self

    def update(self, done: int, total: int) -> None:
        elapsed = time.perf_counter() - self.start
        if elapsed < self.delay or total <= 0:
            return
        percent = int(100 * done / total)
        sys.stderr.write(f"\renvconv: resampling {percent:3d}% ({format_seconds(elapsed)})")
        sys.stderr.flush()
        self._drawn = True

    def __exit__(self, *exc: Any) -> None:
        if not self.tty:
            return
        from ..resample.kernels import watch_progress

        watch_progress(self._previous)
        if self._drawn:
            sys.stderr.write("\r\033[K")
            sys.stderr.flush()
