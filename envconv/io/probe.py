"""Header-only probe of a map: what :func:`envconv.io.read` would give, without a pixel read.

:func:`probe` opens each file's header (every face file of a ``{face}`` path), never its
pixels: it costs a few milliseconds and no memory whatever the image size. It reports the
map's size, channels, pixel type, MIP levels, the file's colour space and metadata as stored,
and the layout as :func:`envconv.io.read` would place it, or why none fits.

One difference from reading: an untagged 2:1 image is reported as ``latlong`` (with
``paraboloid`` among the candidates), where a read also looks at the pixels and asks for
``--from`` when they are black outside two disks (a dual paraboloid).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

from ..errors import ImageIOError, LayoutError
from ..layouts import Layout, get_layout
from ..layouts.detect import find_layout, place_image
from .files import FileHeader, read_file_header

__all__ = ["Probe", "probe"]


@dataclass(frozen=True)
class Probe:
    """The header facts of a map file (or ``{face}`` set), as :func:`probe` finds them.

    ``width`` × ``height`` and ``channels`` are those of the map :func:`envconv.io.read`
    would return (the six faces side by side for ``cube-faces``; an ``A`` added where the
    data window leaves holes). ``levels`` are (width, height) of each MIP level's display
    window, of the first file. ``header`` and ``metadata`` are the first file's, as stored
    (``oiio:ColorSpace`` is the file's, not the working space). ``layout`` is None when no
    layout fits, ``candidates`` and ``reason`` say what was weighed; ``size`` (N) and
    ``guard`` are those of MIP ``level``, None without a layout.
    """

    path: str
    files: tuple[str, ...]
    header: FileHeader
    width: int
    height: int
    channels: tuple[str, ...]
    levels: tuple[tuple[int, int], ...]
    layout: Layout | None
    size: int | None
    guard: int | None
    candidates: tuple[str, ...]
    reason: str

    @property
    def metadata(self) -> dict[str, Any]:
        return self.header.metadata

    @property
    def pixel_type(self) -> str:
        return self.header.pixel_type


def probe(path: str | os.PathLike, layout: str | None = None, level: int = 0,
          part: str | None = None) -> Probe:  # fmt: skip
    """Probe ``path`` (one file, or a ``{face}`` set) from its headers alone.

    Parameters
    ----------
    path : str or path
        Image file, or a multi-file layout's path with ``{face}``.
    layout : str, optional
        The layout (``--from``); detected from metadata and aspect when omitted.
    level : int
        MIP level whose size and guard are reported.
    part : str, optional
        Part of a multi-part file (name or index), as for :func:`envconv.io.read`.

    Raises
    ------
    ImageIOError
        A missing or unreadable file, face files that differ in size or channels.
    LayoutError
        A given ``layout`` the image does not fit (an undetectable one is not an error:
        ``layout`` is None).
    """
    from .reader import mip_levels, read_header

    path = os.fspath(path)
    if "{face}" in path:
        return _probe_faces(path, layout, level, part)
    header = read_file_header(path, level, part, deep=True)
    if header.first.deep:  # described, never read as a map (files.py says why)
        return Probe(path, (path,), header, header.width, header.height, header.channels,
                     ((header.width, header.height),), None, None, None, (),
                     "deep data: any number of samples per pixel, not an image")  # fmt: skip
    width, height, channels, metadata = read_header(path, level, part)
    found, size, guard = None, None, None
    if layout is not None:
        candidates, reason = (get_layout(layout).name,), "given by --from"
    else:
        _, _, candidates, reason = find_layout(width, height, metadata)
    try:
        found, guard, size = place_image(width, height, metadata, layout, level=level)
    except LayoutError:
        if layout is not None:
            raise
    levels = tuple(mip_levels(path, part))
    return Probe(path, (path,), header, width, height, tuple(channels), levels, found, size,
                 guard, tuple(candidates), reason)  # fmt: skip


def _probe_faces(template: str, layout: str | None, level: int, part: str | None) -> Probe:
    """A ``{face}`` set: every file's header, which must agree in size and channels."""
    from .face_files import find_face_files
    from .reader import mip_levels, read_header
    from .sets import read_settled

    files = None  # the set found by the last find()

    def find() -> list[str]:
        nonlocal files
        files = find_face_files(template, layout)
        return files.paths

    heads = read_settled(find, lambda paths: [read_header(p, level, part) for p in paths])
    if len({(w, h, tuple(c)) for w, h, c, _ in heads}) != 1:
        raise ImageIOError(f"the {files.layout} parts of {template} differ in size or channels")
    width, height, channels, metadata = heads[0]
    found = get_layout(files.layout)
    width *= len(files.paths)  # the parts side by side, as a read places them
    _, guard, size = place_image(width, height, metadata, found, level=level)
    header = read_file_header(files.paths[0], level, part)
    levels = tuple(mip_levels(files.paths[0], part))  # of one file, as the windows are
    return Probe(template, tuple(files.paths), header, width, height, tuple(channels), levels,
                 found, size, guard, (found.name,), "{face} in the path: one file per face")  # fmt: skip
