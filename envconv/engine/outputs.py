"""The output policy of every run (``convert``, chains, graph files, batches), in one place.

Checked before any pixel is read or written:

1. No output is an input of the run: not the same path, nor the same file through a symbolic
   or hard link (:func:`os.path.samefile`); a ``{face}`` input counts every face file.
2. No two outputs of one run are one file (within a chain or graph file; across the jobs of a
   batch).
3. With ``no_clobber`` (``-n/--no-clobber``), no output exists yet.
4. Every output can be a file: it is no folder, its name fits the file system (``NAME_MAX``,
   255 bytes on most), and no file stands where one of its folders would be made.

The outputs are every file a run writes: maps, previews, and a batch's ``--report``; the
inputs are every file it reads, the graph file included. Otherwise an output that exists is
replaced atomically: :func:`envconv.io.write` writes a temporary file next to it and renames
it into place (a set of files all at once: :mod:`envconv.io.sets`). Every refusal is a
:class:`~envconv.errors.UsageError` naming the file, but for a file in the way of a folder,
an :class:`~envconv.errors.ImageIOError` ("cannot write"), as the write itself would say.
"""

from __future__ import annotations

import os
from collections.abc import Iterable

from ..errors import ImageIOError, UsageError

__all__ = ["input_files", "check_outputs", "check_file_path", "REPORT"]

#: The owner of a batch's ``--report`` among the outputs of :func:`check_outputs`.
REPORT = "--report"


def input_files(path: str | os.PathLike, layout: str | None = None, faces=None) -> list[str]:
    """The files an input path stands for (:func:`envconv.io.face_files.files_of`); none for
    an incomplete ``{face}`` set, which fails when read and has no file to protect here."""
    from ..errors import EnvconvError
    from ..io.face_files import files_of

    try:
        return files_of(path, layout, faces)
    except EnvconvError:
        return []


def _keys(path: str) -> list:
    """What identifies a file: its absolute path and, when it exists, its device and inode."""
    keys: list = [os.path.normcase(os.path.abspath(path))]
    try:
        stat = os.stat(path)
    except OSError:  # not there (yet)
        return keys
    return [*keys, (stat.st_dev, stat.st_ino)]


def check_outputs(outputs: Iterable[tuple], inputs: Iterable[str]) -> None:
    """Refuse, with UsageError, a run that breaks the policy of this module.

    Parameters
    ----------
    outputs : iterable of (path, no_clobber) or (path, no_clobber, owner)
        Every file the run writes (final names: no ``{face}`` or ``{level}`` left), whether it
        must not exist yet, and optionally what writes it (a batch job's input, named when two
        jobs would write one file; :data:`REPORT` for a batch's report).
    inputs : iterable of str
        Every file the run reads.
    """
    read = {key: path for path in dict.fromkeys(inputs) for key in _keys(path)}
    written: dict = {}
    for path, no_clobber, *owner in outputs:
        keys = _keys(path)
        name = f"{REPORT} {path}" if owner[:1] == [REPORT] else path
        source = next((read[k] for k in keys if k in read), None)
        if source is not None:
            raise UsageError(f"{name} is the input {source}; envconv never writes onto its "
                             "inputs: choose another output path")  # fmt: skip
        other = next((written[k] for k in keys if k in written), None)
        if other is not None:
            hint = "give each output its own path (e.g. with {stem} or {layout})"
            if owner and other[1] and owner[0] != other[1][0]:
                raise UsageError(f"{other[1][0]} and {owner[0]} would both write {path}; {hint}")
            raise UsageError(f"{name} would be written twice in one run; {hint}")
        if no_clobber and os.path.lexists(path):
            raise UsageError(f"{name} exists and -n/--no-clobber keeps it; remove it or drop -n")
        check_file_path(path, name)
        written.update(dict.fromkeys(keys, (path, owner)))


def check_file_path(path: str, name: str | None = None) -> None:
    """Refuse an output ``path`` that cannot be a file (rule 4 of the module docstring);
    ``name`` is how the error names it (default: the path)."""
    from ..io.temps import name_max

    name = name or path
    if os.path.isdir(path):
        raise UsageError(f"{name} is a folder, not a file; give the output a file name")
    folder = os.path.dirname(os.path.abspath(path))
    while not os.path.lexists(folder):
        folder = os.path.dirname(folder)
    if not os.path.isdir(folder):
        raise ImageIOError(f"cannot write {name}: {folder} is a file, not a folder")
    size, limit = len(os.fsencode(os.path.basename(path))), name_max(folder)
    if size > limit:
        raise UsageError(f"{name}: the file name is {size} bytes long and this file system "
                         f"takes at most {limit}; choose a shorter name")  # fmt: skip
