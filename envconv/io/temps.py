"""Temporary files of writes: their names, the set this process has open, and stale ones.

Every output is written to a temporary file in the destination folder and renamed into place
(:mod:`envconv.io.writer`). Its name is hidden and carries a fixed marker, the writer's host,
process id and a random part, and ends with the target's extension (image libraries pick the
format by extension)::

    .sky_cross.envconv-HOST-PID-RANDOM.tmp.exr

* :func:`is_temp_name` recognises them (and the ``.NAME.envconv-PID.tmp.EXT`` names of older
  versions), so ``envconv batch DIR`` and globs never take one as an input.
* :func:`live_temps` are this process's unfinished temporary files: an interrupted run removes
  them on its way out (:mod:`envconv.engine.interrupt`).
* :func:`clean_stale` runs before the first write into a folder: it removes the temporary
  files that a killed run (kill -9, power loss) left there, i.e. those of this host whose
  process is gone. Files of a live process, or of another host (a shared folder written by
  other machines), are left alone unless untouched for :data:`FOREIGN_AGE` seconds.
"""

from __future__ import annotations

import logging
import os
import re
import threading
import time
import zlib

__all__ = ["temp_for", "discard", "temp_path", "is_temp_name", "live_temps", "forget", "clean_stale",
           "FOREIGN_AGE"]  # fmt: skip

log = logging.getLogger(__name__)

#: Seconds after which another host's temporary file counts as abandoned.
FOREIGN_AGE = 24 * 3600

_NAME = re.compile(
    r"^\..+\.envconv-(?:(?P<host>[0-9a-f]{8})-)?(?P<pid>\d+)(?:-[0-9a-f]+)?\.tmp(?:\.[^.]*)?$"
)
_lock = threading.Lock()
_live: set[str] = set()
_cleaned: set[str] = set()


def _host() -> str:
    """This host's id in temporary names: 8 hex digits of a CRC-32 of its name, with no
    hashlib or socket to import at every start. (Older versions took a SHA-1: such a leftover
    on this host counts as another host's, and goes after FOREIGN_AGE.)"""
    name = os.uname().nodename if hasattr(os, "uname") else os.environ.get("COMPUTERNAME", "")
    return f"{zlib.crc32(name.encode('utf-8', 'replace')):08x}"


def temp_path(target: str, directory: str) -> str:
    """A new temporary file name for ``target`` in ``directory``, registered as live.

    Cleans the stale temporary files of ``directory`` first (once per process and folder).
    """
    if directory not in _cleaned:
        _cleaned.add(directory)
        clean_stale(directory)
    stem, ext = os.path.splitext(os.path.basename(target))
    name = f".{stem}.envconv-{_host()}-{os.getpid()}-{os.urandom(4).hex()}.tmp{ext}"
    path = os.path.join(directory, name)
    with _lock:
        _live.add(path)
    return path


def temp_for(target: str) -> str:
    """A temporary file next to ``target``, registered as live; pass it to :func:`discard`
    once it is renamed into place or given up."""
    from ..errors import ImageIOError

    directory = os.path.dirname(os.path.abspath(target))
    if not os.path.isdir(directory):
        raise ImageIOError(f"cannot write {target}: directory {directory} does not exist")
    return temp_path(target, directory)


def discard(temp: str) -> None:
    """Remove ``temp`` if it was not renamed into place; it is no longer live."""
    try:
        os.remove(temp)
    except FileNotFoundError:
        pass
    finally:
        forget(temp)


def forget(path: str) -> None:
    """``path`` is renamed into place or removed: no longer this process's to clean up."""
    with _lock:
        _live.discard(path)


def live_temps() -> list[str]:
    """This process's temporary files that are still being written."""
    with _lock:
        return sorted(_live)


def is_temp_name(name: str) -> bool:
    """True for the file name (not path) of an envconv temporary file."""
    return _NAME.match(os.path.basename(name)) is not None


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):  # someone else's process: alive
        return True
    return True


def clean_stale(directory: str) -> list[str]:
    """Remove the abandoned envconv temporary files in ``directory``; returns those removed."""
    try:
        names = os.listdir(directory)
    except OSError:
        return []
    removed, host, now = [], _host(), time.time()
    for name in names:
        match = _NAME.match(name)
        if match is None:
            continue
        path = os.path.join(directory, name)
        ours = match["host"] in (None, host)
        try:
            if ours and _alive(int(match["pid"])):
                continue
            if not ours and now - os.stat(path).st_mtime < FOREIGN_AGE:
                continue
            os.remove(path)
        except OSError:  # gone already, or not ours to remove
            continue
        removed.append(path)
        log.info("removed %s, left by an interrupted run", path)
    return removed
