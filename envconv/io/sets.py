"""Files replaced together: a reader sees all the new ones or all the old ones.

One output file is replaced by one ``os.replace``, which is atomic. A set (the six files of a
face set, one file per MIP level, or both) would need several, and POSIX has no multi-file
rename, so :func:`replace_files` follows a journal protocol:

1. Every new file is complete in its temporary file, locked (:mod:`envconv.io.temps`).
2. A journal listing each (target, temporary file, backup) is written into every folder the
   set touches, each copy locked; it appears whole (written under a temporary name, renamed).
3. Each existing target gets a backup next to it: a hard link, so the target stays in place
   (or a rename, on file systems without hard links).
4. Each temporary file is renamed onto its target.
5. Commit: the backups are removed, then the journals.

A failure in steps 2-4 (EPERM, ENOSPC, EXDEV, a signal) rolls everything back before the
one-line error: the old files are back, new files that had no old one are removed, and the
folders hold what they held before.

**After a crash** (SIGKILL, the OOM killer) in steps 2-5 the journal stays, unlocked. A reader
that follows the protocol (:func:`read_settled`: envconv reading a ``{face}`` set) repairs it
first, as does the next envconv run writing into that folder (:func:`clean_folder`): if
every new file was already renamed into place the set is kept (forward),
otherwise each old file is restored and each new one removed (back). Either way the set is
whole, old or new, and nothing is left behind. A program that does not follow the protocol
can see a mixed set from the crash until that repair (and, during step 4 of a live run, for
the few milliseconds the renames take). Guarantees hold for a killed process; across a power
loss they hold only as far as the file system keeps renames in order (envconv does not fsync).
"""

from __future__ import annotations

import errno
import logging
import os
import time

from ..errors import ImageIOError
from . import temps

__all__ = [
    "replace_files",
    "read_settled",
    "clean_folder",
    "repair_journal",
    "write_journal",
    "read_journal",
    "restore",
    "WAIT",
]

log = logging.getLogger(__name__)

#: Seconds a reader waits for a live run to finish replacing a set it wants to read.
WAIT = 60.0


def _failed(target: str, exc: OSError) -> ImageIOError:
    return ImageIOError(f"cannot write {target}: {exc.strerror or exc}")


def replace_files(pairs: list[tuple[str, str]], token: str) -> None:
    """Rename each (temporary file, target) of ``pairs`` into place, all or none (see the
    module docstring); ``token`` is the one the temporary files were made with. The temporary
    files are this function's from here on: renamed, or removed with everything undone.

    Raises ImageIOError (one line naming the target) with every target as it was.
    """
    if len(pairs) == 1:
        temp, target = pairs[0]
        try:
            os.replace(temp, target)
        except OSError as exc:
            temps.discard(temp)
            raise _failed(target, exc) from None
        temps.forget(temp)
        return
    temps.withdraw([temp for temp, _ in pairs])  # an interrupted run leaves them to the journal
    entries = [(target, temp, _backup_name(target, token, k)) for k, (temp, target) in
               enumerate(pairs)]  # fmt: skip
    journals: list[str] = []
    try:
        _write_journals(entries, token, journals)
        _swap(entries)
    except BaseException as exc:
        _undo(entries, journals)
        if isinstance(exc, OSError):
            raise _failed(getattr(exc, "target", pairs[0][1]), exc) from None
        raise
    for _, temp, backup in entries:
        temps.forget(temp)
        _remove(backup)
    for journal in journals:
        _remove(journal)
        temps.forget(journal)


def _backup_name(target: str, token: str, index: int) -> str | None:
    """Where the old file of ``target`` goes while the set is replaced; None when there is
    no old file."""
    if not os.path.lexists(target):
        return None
    return temps.side_path(target, token, "-old", variant=index + 1)


def _write_journals(entries, token: str, journals: list[str]) -> None:
    """Step 2: one journal per folder of the set, each locked and whole; ``journals`` lists
    them as they are made (for :func:`_undo`)."""
    folders: dict[str, str] = {}
    for target, _, _ in entries:
        folders.setdefault(os.path.dirname(os.path.abspath(target)), target)
    names = [temps.side_path(target, token, "-journal", "") for target in folders.values()]
    for name, target in zip(names, folders.values(), strict=True):
        part = temps.temp_path(f"{os.path.splitext(target)[0]}.journal", token=token)
        temps.withdraw([part])
        journals.append(part)
        write_journal(part, entries, names)
        temps.rename_held(part, name)
        journals[-1] = name


def _swap(entries) -> None:
    """Steps 3 and 4: back up every old file, then rename every new one into place. An
    OSError carries the target it failed on (``exc.target``)."""
    for target, _, backup in entries:
        if backup is None:
            continue
        try:
            try:
                os.link(target, backup, follow_symlinks=False)
            except OSError as exc:
                if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV,
                                     errno.EMLINK, errno.ENOSYS):  # fmt: skip
                    raise
                os.rename(target, backup)  # no hard links here: the target is away a moment
        except OSError as exc:
            exc.target = target  # type: ignore[attr-defined]
            raise
    for target, temp, _ in entries:
        try:
            os.replace(temp, target)
        except OSError as exc:
            exc.target = target  # type: ignore[attr-defined]
            raise


def _undo(entries, journals: list[str]) -> None:
    """Roll a failed replacement back: old files restored, new ones and temporary files
    removed, journals gone. Where that fails, everything stays for the next run, whose
    repair of the (then dead) journal finishes it: a temporary file not yet renamed is what
    tells it to roll back."""
    try:
        for target, temp, backup in entries:
            if backup is not None and os.path.lexists(backup):
                restore(backup, target)
            elif backup is None and not os.path.lexists(temp) and os.path.lexists(target):
                os.remove(target)  # renamed into place, with no old file to put back
    except OSError as exc:
        log.warning("cannot roll back the set of %s (%s); the next run writing there will",
                    entries[0][0], exc.strerror or exc)  # fmt: skip
        for path in [temp for _, temp, _ in entries] + journals:
            temps.forget(path)  # unlocked and kept: a dead journal with its files
        return
    for _, temp, _ in entries:
        temps.discard(temp)
    for journal in journals:
        _remove(journal)
        temps.forget(journal)


def _remove(path: str | None) -> None:
    if path is not None:
        try:
            os.remove(path)
        except FileNotFoundError:
            pass


# --- the journal: what a dead run leaves, and its repair ----------------------------------


def write_journal(path: str, entries: list[tuple[str, str, str | None]], copies: list[str]) -> None:
    """Write the journal ``path`` of a set: (target, temp, backup or None) of every file and
    the paths of every copy of the journal (one per folder), all relative to its folder."""
    import json  # only where a set is written: not at every start

    base = os.path.dirname(path)

    def rel(p: str | None) -> str | None:
        return None if p is None else os.path.relpath(p, base)

    data = {"envconv-journal": 1, "copies": [rel(c) for c in copies],
            "files": [[rel(t), rel(tmp), rel(b)] for t, tmp, b in entries]}  # fmt: skip
    with open(path, "w", encoding="utf-8") as handle:
        json.dump(data, handle)


def read_journal(path: str) -> tuple[list[tuple[str, str, str | None]], list[str]] | None:
    """(entries, copies) of a journal, absolute; None when it is gone or not a journal."""
    import json

    base = os.path.dirname(path)
    try:
        with open(path, encoding="utf-8") as handle:
            data = json.load(handle)
        entries = [tuple(None if p is None else os.path.normpath(os.path.join(base, p))
                         for p in item) for item in data["files"]]  # fmt: skip
        copies = [os.path.normpath(os.path.join(base, c)) for c in data["copies"]]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return entries, copies  # type: ignore[return-value]


def repair_journal(journal: str) -> str | None:
    """Finish a dead set's replacement, if ``journal`` is one: "back" (old files restored),
    "forward" (the new set kept), or None (its run is alive, another repairs it, or no such
    journal). A set whose every new file was renamed into place is kept; otherwise each old
    file goes back, each new one that had no old file is removed, then every leftover."""
    found = read_journal(journal)
    if found is None:
        return None
    entries, copies = found
    fds = []
    try:
        for copy in sorted(set(copies) | {journal}):  # every copy, in one order: no deadlock
            try:
                fd = os.open(copy, os.O_RDONLY | getattr(os, "O_CLOEXEC", 0))
            except FileNotFoundError:
                continue
            fds.append(fd)
            if temps.try_lock(fd) is False:
                return None  # alive, or being repaired
        return _roll(entries, copies, journal)
    finally:
        for fd in fds:
            os.close(fd)


def _roll(entries, copies, journal: str) -> str:
    """Roll a dead set back or forward (see :func:`repair_journal`); temps go last, so a
    repair killed half-way is finished the same way by the next one."""
    forward = not any(os.path.lexists(temp) for _, temp, _ in entries)
    for target, temp, backup in entries:
        if forward:
            _remove(backup)
        elif backup is not None and os.path.lexists(backup):
            restore(backup, target)
        elif backup is None and not os.path.lexists(temp):
            _remove(target)  # renamed into place, with no old file to restore
    for _, temp, _ in entries:
        _remove(temp)
    for copy in sorted(set(copies) | {journal}):
        _remove(copy)
    way = "forward" if forward else "back"
    log.warning("repaired %s: an interrupted run's set rolled %s", journal, way)
    return way


def restore(backup: str, target: str) -> None:
    """Put the old file ``backup`` back at ``target``. A hard link to the file still there is
    simply removed: rename(2) between two links of one file does nothing."""
    try:
        same = os.path.samestat(os.lstat(backup), os.lstat(target))
    except OSError:
        same = False
    if same:
        os.remove(backup)
    else:
        os.replace(backup, target)


def clean_folder(directory: str) -> None:
    """Repair the dead journals of ``directory``, then remove its abandoned temporary files
    (:func:`envconv.io.temps.clean_stale`): what the next run writing there does first."""
    for journal in temps.journals_in(directory):
        try:
            repair_journal(journal)
        except OSError as exc:  # left for the next run; the folder's other files still go
            log.warning("cannot repair %s: %s", journal, exc.strerror or exc)
    temps.clean_stale(directory)


# --- the reader's side --------------------------------------------------------------------


def _stamps(paths: list[str]) -> list[tuple[int, ...] | None]:
    out = []
    for path in paths:
        try:
            st = os.stat(path)
        except OSError:
            out.append(None)
            continue
        out.append((st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns))
    return out


def _journals_naming(paths: list[str]) -> list[str]:
    """The journals, in the folders of ``paths``, whose sets hold one of them."""
    wanted = {os.path.normpath(os.path.abspath(p)) for p in paths}
    found = []
    for folder in dict.fromkeys(os.path.dirname(p) for p in wanted):
        for journal in temps.journals_in(folder):
            entries = read_journal(journal)
            if entries is not None and any(target in wanted for target, _, _ in entries[0]):
                found.append(journal)
    return found


def read_settled(find, read, wait: float = WAIT):
    """``read(paths)`` of the set ``find()`` names, following the protocol: dead journals
    naming its files are repaired first, a live one is waited for, and a read during which a
    file changed or a journal appeared is done again; ImageIOError after ``wait`` seconds.
    """
    deadline = time.monotonic() + wait
    while True:
        paths = find()
        journals = _journals_naming(paths)
        try:
            busy = [j for j in journals if repair_journal(j) is None and os.path.exists(j)]
        except OSError as exc:
            raise ImageIOError(f"{paths[0]}: cannot repair the set an interrupted run left: "
                               f"{exc.strerror or exc}") from None  # fmt: skip
        if not journals:
            before = _stamps(paths)
            result = read(paths)
            if _stamps(paths) == before and not _journals_naming(paths):
                return result
        if time.monotonic() > deadline:
            raise ImageIOError(f"{paths[0]}: its set is being replaced by another run "
                               f"({(busy or journals)[0]}); try again when it is done")  # fmt: skip
        if busy:
            time.sleep(0.05)
