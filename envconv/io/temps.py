"""Temporary files of writes: their names, their locks, and what a killed run leaves behind.

Every output is written to a temporary file in the destination folder and renamed into place
(:mod:`envconv.io.writer`, :mod:`envconv.io.sets`). Its name is hidden and carries a fixed
marker, the writer's host, process id and a token, and ends with the target's extension (image
libraries pick the format by extension)::

    .sky_cross.envconv-HOST-PID-TOKEN.tmp.exr

The stem is shortened where the name would pass the folder's limit (``NAME_MAX``, 255 bytes on
most file systems), so any legal output name has a legal temporary name. The files of a set
replaced together (:mod:`envconv.io.sets`) share one token with the set's journal
(``….tmp-journal``) and the backups of the old files (``….tmp-old.EXT``).

**Ownership is a lock, not a process id.** The process that makes a temporary file creates
it (``O_EXCL``) and holds a ``flock`` on it until it is renamed into place or removed; the
kernel drops the lock when the process ends, however it ends. :func:`clean_stale` removes a
file exactly when it can take that lock: its owner is gone, whatever PID namespace (container)
it ran in and whatever PID its name carries. :func:`envconv.io.sets.clean_folder` runs it
before the first write into each folder. HOST and PID only tell a person whose file it was.

* Another host's file (a shared folder) must also be untouched for :data:`FOREIGN_AGE`: NFS
  mounted ``nolock`` keeps locks local to each client, where a lock proves nothing.
* On a file system without locks (``flock`` fails: ``ENOLCK``, ``EOPNOTSUPP``; or no
  ``fcntl``, on Windows) files are written unlocked, and only those untouched for
  :data:`FOREIGN_AGE` are removed: a live run there is never mistaken for a dead one, but a
  killed run's file stays a day.
* The files of a set with a journal (:mod:`envconv.io.sets`) are left to its repair, which
  :func:`envconv.io.sets.clean_folder` runs first.

:func:`is_temp_name` recognises every such name (and the ``.NAME.envconv-PID.tmp.EXT`` names of
older versions, which hold no lock), so ``envconv batch DIR`` and globs never take one as an
input; :func:`live_temps` are this process's unfinished files, which an interrupted run removes
on its way out (:mod:`envconv.engine.interrupt`).
"""

from __future__ import annotations

import errno
import logging
import os
import re
import threading
import time
import zlib

try:
    import fcntl
except ImportError:  # Windows: no flock
    fcntl = None  # type: ignore[assignment]

__all__ = ["temp_for", "temp_path", "discard", "forget", "withdraw", "is_temp_name", "live_temps",
           "clean_stale", "new_token", "side_path", "rename_held", "journals_in", "try_lock",
           "FOREIGN_AGE", "NAME_MAX", "name_max"]  # fmt: skip

log = logging.getLogger(__name__)

#: Seconds after which a temporary file whose lock proves nothing counts as abandoned.
FOREIGN_AGE = 24 * 3600
#: The longest file name, in bytes, where the file system does not say (``PC_NAME_MAX``).
NAME_MAX = 255

_NAME = re.compile(
    r"^\..+\.envconv-(?:(?P<host>[0-9a-f]{8})-)?(?P<pid>\d+)(?:-(?P<token>[0-9a-f]+))?"
    r"\.tmp(?P<kind>-old|-journal)?(?:\.[^.]*)?$"
)
_lock = threading.Lock()
_live: dict[str, int | None] = {}  # path -> the descriptor holding its lock (None: no lock)
_held: dict[str, int | None] = {}  # withdrawn from _live (a set being committed), still locked


def _host() -> str:
    """This host's id in temporary names: 8 hex digits of a CRC-32 of its name, with no
    hashlib or socket to import at every start. (Older versions took a SHA-1: such a leftover
    on this host counts as another host's, and goes after FOREIGN_AGE.)"""
    name = os.uname().nodename if hasattr(os, "uname") else os.environ.get("COMPUTERNAME", "")
    return f"{zlib.crc32(name.encode('utf-8', 'replace')):08x}"


def new_token() -> str:
    """A random token: the files of one write (or one set) share it."""
    return os.urandom(4).hex()


def name_max(directory: str) -> int:
    """The longest file name, in bytes, the file system of ``directory`` takes."""
    try:
        return int(os.pathconf(directory, "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):
        return NAME_MAX


def side_path(target: str, token: str, kind: str = "", extension: str | None = None,
              variant: int = 0) -> str:  # fmt: skip
    """The name next to ``target`` of its temporary file (``kind`` ``""``), backup (``"-old"``)
    or journal (``"-journal"``) under ``token``; the stem is cut to fit the folder's limit, and
    ``variant`` n > 0 ends it with ``~n`` (two long names cut to one stem)."""
    directory = os.path.dirname(os.path.abspath(target))
    stem, ext = os.path.splitext(os.path.basename(target))
    ext = ext if extension is None else extension
    tail = f"~{variant}" if variant else ""
    suffix = f"{tail}.envconv-{_host()}-{os.getpid()}-{token}.tmp{kind}{ext}"
    room = max(1, name_max(directory) - 1 - len(suffix.encode("utf-8", "surrogateescape")))
    short = stem.encode("utf-8", "surrogateescape")[:room].decode("utf-8", "ignore") or "x"
    return os.path.join(directory, f".{short}{suffix}")


def try_lock(fd: int, blocking: bool = False) -> bool | None:
    """Take an exclusive flock on ``fd``: True, False when another holds it, None when this
    file system (or platform) has no locks."""
    if fcntl is None:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
    except BlockingIOError:
        return False
    except OSError as exc:
        if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            return False
        return None  # ENOLCK, EOPNOTSUPP, EINVAL: no locks here
    return True


def _same_file(path: str, fd: int) -> bool:
    try:
        a, b = os.stat(path), os.fstat(fd)
    except OSError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def temp_path(target: str, directory: str | None = None, token: str | None = None) -> str:
    """Create (empty), lock and register a new temporary file for ``target``; return its path.

    Raises OSError when it cannot be created (no folder, no permission, a read-only file
    system). The lock is held until :func:`discard` (or :func:`forget` after a rename).
    """
    target = os.path.join(directory, os.path.basename(target)) if directory else target
    token = token or new_token()
    for variant in range(16):
        path = side_path(target, token, variant=variant)
        # Live before it exists: a signal raised (envconv.engine.interrupt) between the
        # creation and the return must still find it among this process's unfinished files.
        with _lock:
            mine = path not in _live and path not in _held
            if mine:
                _live[path] = None
        if not mine:  # this process's own file (a token drawn twice, two names cut to one)
            continue
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0),
                         0o666)  # fmt: skip
        except FileExistsError:  # two long names cut to one stem, or a token drawn twice
            _release(path)
            continue
        except OSError:  # not made (an interruption keeps it live: it may have been)
            _release(path)
            raise
        locked = try_lock(fd, blocking=True)  # a cleaner testing it holds it for a moment
        if locked and not _same_file(path, fd):  # removed under us before we locked it
            os.close(fd)
            _release(path)
            continue
        if not locked:
            os.close(fd)  # nothing to hold (on Windows, an open file cannot be renamed)
            fd = None
        with _lock:
            _live[path] = fd
        return path
    raise FileExistsError(errno.EEXIST, "no free temporary name", target)


def temp_for(target: str, token: str | None = None) -> str:
    """A temporary file next to ``target`` (see :func:`temp_path`); ImageIOError in one line
    when it cannot be made."""
    from ..errors import ImageIOError

    directory = os.path.dirname(os.path.abspath(target))
    if not os.path.isdir(directory):
        raise ImageIOError(f"cannot write {target}: directory {directory} does not exist")
    try:
        return temp_path(target, token=token)
    except OSError as exc:
        raise ImageIOError(f"cannot write {target}: {exc.strerror or exc}") from None


def _release(path: str) -> None:
    with _lock:
        fd = _live.pop(path, None) if path in _live else _held.pop(path, None)
    if fd is not None:
        os.close(fd)


def discard(temp: str) -> None:
    """Remove ``temp`` if it was not renamed into place, and drop its lock."""
    try:
        os.remove(temp)
    except FileNotFoundError:
        pass
    finally:
        _release(temp)


def forget(path: str) -> None:
    """``path`` was renamed into place or removed: drop its lock; no longer this process's."""
    _release(path)


def withdraw(paths) -> None:
    """Keep the locks of ``paths`` but leave them out of :func:`live_temps`: a set being
    committed, which an interrupted run must leave to its journal rather than delete."""
    with _lock:
        for path in paths:
            if path in _live:
                _held[path] = _live.pop(path)


def rename_held(old: str, new: str) -> None:
    """Rename this process's ``old`` (withdrawn or live) to ``new``, keeping its lock: a
    journal appears whole, under its own name."""
    os.replace(old, new)
    with _lock:
        if old in _live:
            _held[new] = _live.pop(old)
        elif old in _held:
            _held[new] = _held.pop(old)


def live_temps() -> list[str]:
    """This process's temporary files that are still being written."""
    with _lock:
        return sorted(_live)


def is_temp_name(name: str) -> bool:
    """True for the file name (or path) of an envconv temporary file, backup or journal."""
    return _NAME.match(os.path.basename(name)) is not None


def journals_in(directory: str, names: list[str] | None = None) -> list[str]:
    """Paths of the set journals in ``directory`` (of its listing ``names`` when given)."""
    if names is None:
        try:
            names = os.listdir(directory)
        except OSError:
            return []
    found = [n for n in names if (m := _NAME.match(n)) is not None and m["kind"] == "-journal"]
    return [os.path.join(directory, n) for n in sorted(found)]


def clean_stale(directory: str) -> list[str]:
    """Remove the abandoned temporary files of ``directory`` (see the module docstring), but
    those of a set with a journal, which :func:`envconv.io.sets.clean_folder` repairs first;
    returns the paths removed."""
    try:
        names = os.listdir(directory)
    except OSError:
        return []
    removed, held = [], []
    try:
        for name in names:
            match = _NAME.match(name)
            path = os.path.join(directory, name)
            if match is None or match["kind"] == "-journal" or path in _live or path in _held:
                continue
            fd = _claim(path, match)
            if fd is not None:
                held.append((path, match.group("host", "pid", "token"), fd))
        # A set's journal, even one made since the listing, speaks for its files.
        sets = {_NAME.match(os.path.basename(j)).group("host", "pid", "token")
                for j in journals_in(directory)}  # fmt: skip
        for path, owner, fd in held:
            if owner in sets or not _same_file(path, fd):
                continue
            try:
                os.remove(path)
            except OSError:  # not ours to remove
                continue
            removed.append(path)
            log.info("removed %s, left by an interrupted run", path)
    finally:
        for _, _, fd in held:
            os.close(fd)
    return removed


def _claim(path: str, match: re.Match) -> int | None:
    """An open descriptor of ``path`` holding its lock when its owner is gone (see the
    module docstring), else None."""
    try:
        flags = os.O_RDONLY | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_NOFOLLOW", 0)
        fd = os.open(path, flags | getattr(os, "O_NONBLOCK", 0))  # a FIFO must not block
    except OSError:
        return None
    try:
        locked = try_lock(fd)
        old = time.time() - os.fstat(fd).st_mtime >= FOREIGN_AGE
        ours = match["host"] in (None, _host())
        if locked is False or (locked is None and not old) or (not ours and not old):
            os.close(fd)
            return None
    except OSError:
        os.close(fd)
        return None
    return fd
