"""How errors read on the command line: one line, and a "did you mean" where a name is close.

:mod:`envconv.cli.main` turns every error into one line on stderr; this module shapes that
line. :func:`one_line` folds a message of several lines (click's "Choose from:" lists, a
library's own lines) into one; :func:`did_you_mean` finds the names close to a typo;
:func:`show_warning` prints a Python warning (numpy's) as one ``envconv: warning:`` line;
:func:`echo_result` is the one place results reach stdout;
:func:`step_typo` finds, in the arguments of a chained step, a word that is a misspelt step name
(``envconv read sky.exr resampel --to latlong``), which click would otherwise report as an
unknown option of the step before it.
"""

from __future__ import annotations

import difflib
import os
import re
import sys

import click

from ..errors import EnvconvError

__all__ = ["one_line", "did_you_mean", "step_typo", "show_warning", "echo_result", "StdoutError",
           "stdout_failed"]  # fmt: skip


class StdoutError(EnvconvError):
    """Results could not be written on stdout (a full disk, ``/dev/full``, an I/O error)."""


def echo_result(line: str = "") -> None:
    """Print one line of results on stdout: the one place the command line writes results.

    A stdout that cannot take it raises :class:`StdoutError` ("cannot write to stdout: No
    space left on device": one line on stderr, exit 1) after pointing descriptor 1 at
    ``/dev/null``, so that the interpreter's last flush cannot fail again. A closed pipe
    (``envconv layouts | head``) is click's to end quietly.
    """
    try:
        click.echo(line)
    except BrokenPipeError:
        raise
    except OSError as exc:
        raise stdout_failed(exc) from None


def stdout_failed(exc: OSError) -> StdoutError:
    """The error for a failed write on stdout; what is still buffered is dropped."""
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.close(null)
    except OSError:
        pass
    return StdoutError(f"cannot write to stdout: {exc.strerror or exc}")


def one_line(message: str) -> str:
    """``message`` on one line: its non-empty lines joined by a space, runs of blanks as one."""
    lines = [re.sub(r"\s+", " ", line).strip() for line in str(message).splitlines()]
    return " ".join(line for line in lines if line) or "unknown error"


def did_you_mean(word: str, names, cutoff: float = 0.6) -> str:
    """``"; did you mean 'x'?"`` (or ``'x' or 'y'``) for the names close to ``word``, else ``""``."""
    close = difflib.get_close_matches(str(word).lower(), list(names), n=2, cutoff=cutoff)
    if not close:
        return ""
    return "; did you mean " + " or ".join(f"'{name}'" for name in close) + "?"


def step_typo(args: list[str], names) -> str | None:
    """The first word of ``args`` that is not an option and is close to a step name in
    ``names`` but is not one: a misspelt step (file names, which have a dot or a slash, and
    numbers are never taken for one)."""
    names = list(names)
    for token in args:
        if token.startswith("-") or "." in token or "/" in token or token in names:
            continue
        if difflib.get_close_matches(token.lower(), names, n=1, cutoff=0.75):
            return token
    return None


def show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A Python warning as one line, ``envconv: warning: Category: text (file.py:N)``
    (``warnings.showwarning`` of the command line; the default prints the source line too)."""
    stream = file if file is not None else sys.stderr
    if stream is None:
        return
    where = f"{os.path.basename(str(filename))}:{lineno}"
    try:
        stream.write(f"envconv: warning: {category.__name__}: {one_line(str(message))} ({where})\n")
    except (OSError, ValueError):
        pass
