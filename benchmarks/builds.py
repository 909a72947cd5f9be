"""Helpers for benchmarks that compare builds: interpreters, timed children, inputs, a table.

A *build* is a Python interpreter (usually a venv's ``bin/python``); its envconv is whatever
that interpreter imports from a scratch directory. Children are timed from start to exit, with
their own peak resident memory (``ru_maxrss`` from ``os.wait4``).
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

__all__ = [
    "EXAMPLES", "Build", "Table", "spawn", "run_logged", "median", "clone_head", "latlong_file",
    "batch_inputs", "remove",
]  # fmt: skip

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLES = os.path.join(ROOT, "examples", "data")

_WHERE = (
    "import envconv, os; print(os.path.dirname(os.path.dirname(os.path.abspath(envconv.__file__))))"
)


@dataclass
class Build:
    """One interpreter to measure: ``source`` is the root of its envconv tree, None for a peer."""

    name: str
    python: str
    source: str | None = None

    @classmethod
    def envconv_build(cls, name: str, python: str) -> Build:
        """The build ``python`` imports, with its package's bytecode compiled (as an install does)."""
        python = os.path.abspath(python)  # not realpath: a venv's python is a symlink
        with tempfile.TemporaryDirectory() as scratch:
            proc = subprocess.run(
                [python, "-c", _WHERE], cwd=scratch, capture_output=True, text=True
            )
        if proc.returncode:
            raise SystemExit(
                f"{python} cannot import envconv: {proc.stderr.strip().splitlines()[-1:]}"
            )
        source = proc.stdout.strip()
        subprocess.run(
            [python, "-m", "compileall", "-q", os.path.join(source, "envconv")], check=True
        )
        return cls(name, python, source)

    @property
    def envconv(self) -> str:
        """The ``envconv`` console script of this build's venv."""
        return os.path.join(os.path.dirname(self.python), "envconv")


@dataclass
class Table:
    """The summary: one line per target, a figure per build, the target and whether it is met."""

    rows: list[tuple[str, dict[str, str], str, str]] = field(default_factory=list)

    def add(self, what: str, target: str, met: bool | None, **figures: str) -> None:
        self.rows.append((what, figures, target, {True: "yes", False: "NO", None: "?"}[met]))

    def markdown(self) -> str:
        names = ["baseline", "this", "peer"]
        lines = [
            "| what | " + " | ".join(names) + " | target | met |",
            "|---" * (len(names) + 3) + "|",
        ]
        for what, figures, target, met in self.rows:
            cells = [figures.get(name, "") for name in names]
            lines.append(f"| {what} | " + " | ".join(cells) + f" | {target} | {met} |")
        return "\n".join(lines)


def spawn(cmd: list[str], cwd: str, env: dict | None = None) -> tuple[float, float]:
    """Run ``cmd``; return (wall seconds, the child's own peak RSS in MB). Exits on failure."""
    with tempfile.TemporaryFile("w+") as err:
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        elapsed = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode:
            err.seek(0)
            raise SystemExit(f"failed ({proc.returncode}): {' '.join(cmd)}\n{err.read()[-2000:]}")
    return elapsed, usage.ru_maxrss / 1024


def run_logged(cmd: list[str], cwd: str, log: str, env: dict | None = None) -> tuple[float, int]:
    """Run ``cmd`` with its output in the file ``log``; return (wall seconds, exit code)."""
    start = time.perf_counter()
    with open(log, "w") as out:
        code = subprocess.run(
            cmd, cwd=cwd, env=env, stdout=out, stderr=subprocess.STDOUT
        ).returncode
    return time.perf_counter() - start, code


def median(values: list[float]) -> float:
    return statistics.median(values) if values else float("nan")


def clone_head(source: str, dest: str) -> str:
    """Clone the committed HEAD of the git tree ``source`` into ``dest``; return its commit.

    Warns when ``source`` has uncommitted changes to tracked files (they are not cloned)."""
    head = subprocess.run(["git", "-C", source, "rev-parse", "HEAD"], capture_output=True,
                          text=True, check=True).stdout.strip()  # fmt: skip
    dirty = subprocess.run(["git", "-C", source, "status", "--porcelain", "--untracked-files=no"],
                           capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    if dirty:
        print(
            f"warning: {source} has uncommitted changes; measuring its HEAD {head[:10]}",
            file=sys.stderr,
        )
    subprocess.run(["git", "clone", "--quiet", "--no-checkout", source, dest], check=True)
    subprocess.run(["git", "-C", dest, "checkout", "--quiet", head], check=True)
    return head


def latlong_file(path: str, height: int, compression: str | None = None, yaw: float = 0.0,
                 example: str = "park-latlong-512.exr") -> str:  # fmt: skip
    """Write an example upsampled to a float lat-long 2·height × height EXR (once) at ``path``."""
    if not os.path.exists(path):
        import envconv

        source = envconv.read(os.path.join(EXAMPLES, example))
        big = envconv.convert(source, "latlong", size=height, samples=1, rotate=(yaw, 0, 0))
        envconv.write(big, path, bit_depth="float", compression=compression)
    return path


def batch_inputs(folder: str, files: int, height: int = 1024) -> str:
    """``files`` float lat-longs in ``folder``: the examples in turn, each under several yaws."""
    examples = sorted(p for p in os.listdir(EXAMPLES) if p.endswith(".exr"))
    os.makedirs(folder, exist_ok=True)
    for k in range(files):
        name = examples[k % len(examples)]
        yaw = 360.0 * (k // len(examples)) / max(1, files // len(examples))
        latlong_file(os.path.join(folder, f"{k:02d}_{name}"), height, yaw=yaw, example=name)
    return folder


def remove(path: str) -> None:
    """Delete a file or a folder if it is there."""
    if os.path.isdir(path):
        shutil.rmtree(path)
    elif os.path.exists(path):
        os.remove(path)
