"""Shared checks for the fault suite (tests/test_hostile.py): how a failed run must look.

Every hostile case runs the real ``envconv`` console script in a subprocess (so exit codes,
signals, file descriptors and stray output from C++ libraries are the real ones) and then
checks the same things: the exit status, exactly one line on stderr starting with
``envconv: error:``, no traceback, nothing on stdout, no temporary files left behind, and the
input (and any old output) untouched.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Run", "envconv", "snapshot", "assert_failed_cleanly", "assert_untouched", "litter"]

#: The console script of the venv running the tests.
ENVCONV = shutil.which("envconv", path=os.path.dirname(sys.executable)) or "envconv"


@dataclass
class Run:
    """A finished ``envconv`` process: its exit status and its two output streams."""

    args: list[str]
    returncode: int
    stdout: str
    stderr: str

    @property
    def stderr_lines(self) -> list[str]:
        return [line for line in self.stderr.splitlines() if line.strip()]


def envconv(*args, cwd=None, timeout: float = 120, env=None, **popen) -> Run:
    """Run ``envconv ARGS`` in a subprocess; return its :class:`Run` (never raises on failure)."""
    argv = [ENVCONV, *map(str, args)]
    done = subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, **(env or {})}, **popen)  # fmt: skip
    return Run(argv, done.returncode, done.stdout, done.stderr)


def snapshot(*paths) -> dict[str, tuple[int, bytes] | None]:
    """(mtime in ns, bytes) of each path (None where missing), to prove later that none changed."""
    state = {}
    for path in map(Path, paths):
        state[str(path)] = (path.stat().st_mtime_ns, path.read_bytes()) if path.is_file() else None
    return state


def assert_untouched(before: dict[str, tuple[int, bytes] | None]) -> None:
    """Every path of a :func:`snapshot` still has the same bytes and mtime (or is still missing)."""
    assert snapshot(*before) == before, "an input or an old output was changed"


def litter(*folders) -> list[str]:
    """Files envconv may have left behind in ``folders``: its temporary files."""
    found = []
    for folder in map(Path, folders):
        found += [str(p) for p in folder.rglob("*") if ".envconv" in p.name and "tmp" in p.name]
    return found


def assert_failed_cleanly(run: Run, status: int, *folders, message: str | None = None) -> None:
    """``run`` exited with ``status`` after one ``envconv: error:`` line on stderr (containing
    ``message`` when given), printed nothing on stdout and left no temporary file in ``folders``."""
    lines = run.stderr_lines
    assert run.returncode == status, (run.returncode, run.stderr)
    assert "Traceback" not in run.stderr, run.stderr
    assert run.stdout == "", f"stdout must carry results only, got {run.stdout!r}"
    assert len(lines) == 1 and lines[0].startswith("envconv: error: "), lines
    if message is not None:
        assert message.lower() in lines[0].lower(), lines[0]
    assert not litter(*folders), litter(*folders)
