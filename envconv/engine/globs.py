"""Glob patterns of batch inputs: ``**`` walks each real folder once, never into a link cycle.

Python's ``glob.glob(pattern, recursive=True)`` follows links to folders under ``**`` with no
memory of where it has been: a link back up the tree (``tree/a/up -> ..``) is walked again
and again until the paths grow too long, and two such links multiply the walk beyond any wait
(``envconv batch 'tree/**/*.exr'`` never returned). :func:`glob_files` walks as a user means:

* a link to a file is a file like any other (it is matched by its own name);
* a link to a folder is followed, so a library of maps linked into a project is found, but
  each real folder (device and inode) is walked once per ``**``: a cycle ends where it closes,
  and a folder reached by two paths is listed under the first in sorted order;
* hidden folders and files (a leading dot) are matched only by a pattern that names them, as
  ``glob`` and the shells do.

Outside ``**``, the pattern is ``glob.glob``'s (``*``, ``?``, ``[...]``).
"""

from __future__ import annotations

import glob
import os

__all__ = ["glob_files"]


def glob_files(pattern: str) -> list[str]:
    """Files matching ``pattern``, sorted, spelt from the pattern; see the module docstring
    for ``**`` and links."""
    parts = pattern.split(os.sep)
    if "**" not in parts:
        return sorted(p for p in glob.glob(pattern) if os.path.isfile(p))
    at = parts.index("**")
    head = os.sep.join(parts[:at]) or (os.sep if pattern.startswith(os.sep) else os.curdir)
    rest = os.sep.join(parts[at + 1 :]) or "*"
    roots = sorted(glob.glob(head)) if glob.has_magic(head) else [head]
    found: set[str] = set()
    for root in roots:
        for folder in _folders_once(root):
            found.update(glob_files(os.path.join(glob.escape(folder), rest)))
    return sorted(found)


def _folders_once(root: str) -> list[str]:
    """``root`` and the folders under it, each real folder once: under its own path where one
    leads there without a link, else under the first link (sorted) that does. Links to
    folders are followed; hidden folders are skipped; a cycle ends where it closes."""
    seen: set[tuple[int, int]] = set()
    folders: list[str] = []
    plain, linked = [root], []
    while plain or linked:
        folder = plain.pop() if plain else linked.pop(0)
        try:
            info = os.stat(folder)
        except OSError:  # a dangling link, a folder removed meanwhile
            continue
        if (info.st_dev, info.st_ino) in seen:
            continue
        seen.add((info.st_dev, info.st_ino))
        folders.append(folder)
        for entry in _subfolders(folder):
            (linked if entry.is_symlink() else plain).append(entry.path)
        linked.sort()
    return folders


def _subfolders(folder: str) -> list[os.DirEntry]:
    """The folders in ``folder`` (links to folders included), hidden ones left out."""
    try:
        with os.scandir(folder) as entries:
            return [e for e in entries if not e.name.startswith(".") and _is_dir(e)]
    except OSError:  # unreadable: its files cannot be inputs either
        return []


def _is_dir(entry: os.DirEntry) -> bool:
    try:
        return entry.is_dir()  # a link to a folder counts
    except OSError:
        return False
