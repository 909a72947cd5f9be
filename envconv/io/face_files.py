"""The files of multi-file maps: ``{face}`` paths, their face sets, and reading the six parts.

A ``{face}`` path names one file per face. ``cube-faces`` files are named by a face set
(:mod:`envconv.layouts.facesets`: envconv's own px … nz, Quake's ft bk lf rt up dn, Unity's Front …);
``paraboloid-split`` files are front and back. When the caller names no face set, the set is
found from the files that exist: exactly one complete set of names must match. A set whose
names are all part of a larger matching set gives way to it (front and back of a Unity skybox
are not a paraboloid); sets with the same names and the same faces (envconv and three.js) are
one. File names match case-insensitively when the exact name does not exist (Source's
``skyBK.vtf``, Unity's ``Front.png``).
"""

from __future__ import annotations

import os
import re
from typing import NamedTuple

from ..errors import ImageIOError, LayoutError
from ..layouts import get_layout
from ..layouts.facesets import FACE_SETS, FaceSet, get_face_set

__all__ = ["FaceFiles", "find_face_files", "face_path", "face_glob", "part_path", "first_file",
           "files_of", "escape_braces", "has_placeholder", "fill_placeholder", "literal_path"]  # fmt: skip

#: An output path's own placeholders, and the doubled braces that stand for one brace.
_TOKEN = re.compile(r"\{\{|\}\}|\{(face|level)\}")

_CUBE = "cube-faces"
_PARABOLOID = "paraboloid-split"


class FaceFiles:
    """The resolved parts of a ``{face}`` path: layout, face set (cube-faces) and file paths."""

    __slots__ = ("layout", "face_set", "paths")

    def __init__(self, layout: str, face_set: FaceSet | None, paths: list[str]) -> None:
        self.layout, self.face_set, self.paths = layout, face_set, paths


class _Candidate(NamedTuple):
    layout: str
    face_set: FaceSet | None
    names: tuple[str, ...]

    @property
    def label(self) -> str:
        return self.face_set.name if self.face_set is not None else self.layout


#: The placeholder of a multi-file path.
FACE = "{face}"


def face_path(template: str, name: str) -> str:
    """``template`` with ``{face}`` replaced by ``name`` (``sky_{face}.exr``, ``px`` →
    ``sky_px.exr``): the one home of that expansion for inputs (reading, batches); an output
    path, whose doubled braces are literal ones, is filled by :func:`fill_placeholder`."""
    return template.replace(FACE, name)


def face_glob(template: str) -> str:
    """A glob that matches every file of a ``{face}`` template: the template's own glob
    characters escaped and ``{face}`` matching any name."""
    import glob

    return face_path(glob.escape(template), "*")


def escape_braces(text: str) -> str:
    """``text`` (a file name put into an output path) with each brace doubled, so that a
    ``{level}`` or ``{face}`` in it stays literal: ``a{level}`` → ``a{{level}}``."""
    return text.replace("{", "{{").replace("}", "}}")


def has_placeholder(path: str, name: str) -> bool:
    """True when the output path ``path`` holds the placeholder ``{name}`` (``face`` or
    ``level``), not counting escaped braces (``{{level}}`` is literal)."""
    return any(m.group(1) == name for m in _TOKEN.finditer(path))


def fill_placeholder(path: str, name: str, value: str) -> str:
    """``path`` with every ``{name}`` placeholder replaced by ``value``; escapes are kept."""
    return _TOKEN.sub(lambda m: value if m.group(1) == name else m.group(0), path)


def literal_path(path: str) -> str:
    """The file name an output path stands for once its placeholders are filled: doubled
    braces become single ones."""
    return re.sub(r"\{\{|\}\}", lambda m: m.group(0)[0], path)


def part_path(template: str, name: str, listing: dict | None = None) -> str:
    """``template`` with ``{face}`` replaced by ``name`` (:func:`face_path`); an existing file
    that differs only in case stands in for a missing exact name. ``listing`` caches
    directory listings."""
    path = face_path(template, name)
    if os.path.exists(path):
        return path
    directory, base = os.path.split(path)
    listing = {} if listing is None else listing
    if directory not in listing:
        try:
            listing[directory] = {n.lower(): n for n in os.listdir(directory or ".")}
        except OSError:
            listing[directory] = {}
    found = listing[directory].get(base.lower())
    return os.path.join(directory, found) if found else path


def _candidates(layout: str | None) -> list[_Candidate]:
    cands = []
    if layout in (None, _CUBE):
        for face_set in FACE_SETS.values():
            cands.append(_Candidate(_CUBE, face_set, face_set.names))
    if layout in (None, _PARABOLOID):
        cands.append(_Candidate(_PARABOLOID, None, get_layout(_PARABOLOID).face_names))
    return cands


def _same(a: _Candidate, b: _Candidate) -> bool:
    """Same files holding the same faces the same way (envconv and three.js)."""

    def faces(c):
        return c.face_set.transforms if c.face_set is not None else None

    return a.layout == b.layout and a.names == b.names and faces(a) == faces(b)


def find_face_files(template: str, layout: str | None = None, faces=None) -> FaceFiles:
    """Resolve the parts of ``template`` (which holds ``{face}``).

    Parameters
    ----------
    template : str
        Path with ``{face}``.
    layout : str, optional
        ``cube-faces`` or ``paraboloid-split``; found from the files when omitted.
    faces : str or FaceSet, optional
        The face set of a ``cube-faces`` map; found from the files when omitted.

    Raises
    ------
    LayoutError
        A face set with a layout other than cube-faces, or files that match several face sets.
    ImageIOError
        No complete set of files exists.
    """
    if layout is not None and not get_layout(layout).multi_file:
        raise LayoutError(f"{{face}} in the path needs a multi-file layout, not {layout}")
    listing: dict = {}
    if faces is not None:
        if layout not in (None, _CUBE):
            raise LayoutError(
                f"face set {get_face_set(faces).name} applies to {_CUBE}, not {layout}"
            )
        face_set = get_face_set(faces)
        return FaceFiles(_CUBE, face_set, [part_path(template, n, listing) for n in face_set.names])
    complete, partial = [], []
    for cand in _candidates(layout):
        paths = [part_path(template, n, listing) for n in cand.names]
        present = [os.path.exists(p) for p in paths]
        if all(present):
            complete.append((cand, paths))
        partial.append((sum(present), cand, paths))
    unique = []
    for cand, paths in complete:
        if not any(_same(cand, other) for other, _ in unique):
            unique.append((cand, paths))
    unique = [(c, p) for c, p in unique
              if not any(set(c.names) < set(o.names) for o, _ in unique)]  # fmt: skip
    if len(unique) == 1:
        cand, paths = unique[0]
        return FaceFiles(cand.layout, cand.face_set, paths)
    if unique:
        names = ", ".join(f"{c.label} ({' '.join(c.names)})" for c, _ in unique)
        raise LayoutError(
            f"{template} matches several face sets: {names}; name one with --in-convention "
            "(envconv.read(..., faces=NAME))"
        )
    raise ImageIOError(_missing_message(template, partial))


def _missing_message(template: str, partial) -> str:
    count, cand, paths = max(partial, key=lambda item: item[0])
    if count:
        missing = ", ".join(p for p in paths if not os.path.exists(p))
        return f"{template}: the {cand.label} face files are incomplete: no {missing}"
    sets = "; ".join(f"{c.label}: {' '.join(c.names)}" for _, c, _ in partial)
    return f"no files match {template} (face names tried: {sets})"


def files_of(path: str | os.PathLike, layout: str | None = None, faces=None) -> list[str]:
    """The files a (possibly ``{face}``) input path stands for: itself, or every file of the
    face set :func:`find_face_files` finds (the one home of that rule)."""
    path = os.fspath(path)
    if "{face}" not in path:
        return [path]
    return list(find_face_files(path, layout, faces).paths)


def first_file(path: str | os.PathLike, layout: str | None = None, faces=None) -> str:
    """The file whose header stands for a (possibly ``{face}``) input path."""
    return files_of(path, layout, faces)[0]
