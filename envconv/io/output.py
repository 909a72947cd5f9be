"""Every file envconv writes goes through here: temporary files whose every result is checked,
renamed into place as one set.

* :func:`write_files`: one temporary file per target, next to it and locked
  (:mod:`envconv.io.temps`), filled by the caller, then renamed all at once or not at all
  (:func:`envconv.io.sets.replace_files`). On any failure the temporary files go, the targets
  are as they were, and the error is one line naming the target.
* :func:`write_images`: OpenImageIO's writes of one file. The formats whose encoders write front
  to back (:data:`STREAMED`: PNG, JPEG, HDR) write into a pipe, which a thread of this module
  copies into the file with every ``write`` and the ``close`` checked: OpenImageIO's PNG writer
  reports a failed ``fwrite`` (``EFBIG``, ``ENOSPC``) only through ``geterror`` while
  ``write_scanlines`` and ``close`` return True, and libjpeg's default error handler, which
  OpenImageIO's JPEG writer keeps, calls ``exit(1)`` (no message, the temporary file left).
  Nothing fails on a pipe. The others (EXR, TIFF: they seek back to finish their headers) are
  written by OpenImageIO, whose ``open``, band writes and ``close`` return False on a failed
  write (tests/test_hostile.py, full disk). ``has_error`` is no test: the TIFF writer leaves
  a message there on success ("failed TIFFWriteCustomDirectory() of the Exif data").
  TGA's writer seeks and ignores a failed write: its file is checked once closed
  (:data:`CHECKED_AFTER`: the TGA 2.0 footer it writes last, and its reader opening it).
* :func:`write_bytes`: bytes made in memory (DDS, KTX2, JSON reports, HTML pages).
"""

from __future__ import annotations

import os
import threading

from ..errors import ImageIOError
from .chatter import library_output
from .files import _first_line, _oiio
from .formats import format_of
from .sets import clean_folder, replace_files
from .temps import discard, new_token, temp_for

__all__ = [
    "write_files",
    "write_images",
    "write_bytes",
    "STREAMED",
    "CHECKED_AFTER",
    "WRITE_BAND_BYTES",
]

#: OpenImageIO formats whose encoders write front to back: written through a pipe.
STREAMED = ("png", "jpeg", "hdr")
#: Formats whose OpenImageIO writer seeks (no pipe) and ignores a failed write: checked once
#: closed, by what a whole file ends with. TGA: rows stored bottom-up by seeking, and the
#: TGA 2.0 footer written last.
CHECKED_AFTER = {"targa": b"TRUEVISION-XFILE.\0"}
_CLEANED: set[str] = set()

#: Bytes of pixels handed to OIIO per call. One whole-image ``write_image`` made OIIO's PNG
#: writer hold about nine times the image (docs/memory.md); bands of rows cost one band.
WRITE_BAND_BYTES = 1 << 24


def write_files(targets: list[str], write) -> list[str]:
    """Write every file of ``targets`` through a temporary file: ``write(temp, target, index)``
    fills each; then all are renamed into place together. Returns ``targets``."""
    token = new_token()
    written: list[tuple[str, str]] = []
    for folder in dict.fromkeys(os.path.dirname(os.path.abspath(t)) for t in targets):
        if folder not in _CLEANED and os.path.isdir(folder):
            _CLEANED.add(folder)
            clean_folder(folder)  # once per process and folder: what a killed run left
    try:
        for index, target in enumerate(targets):
            temp = temp_for(target, token)
            written.append((temp, target))
            write(temp, target, index)
    except BaseException:
        for temp, _ in written:
            discard(temp)
        raise
    replace_files(written, token)
    return targets


def write_bytes(data: bytes, path: str | os.PathLike) -> str:
    """Write ``data`` to ``path`` through a temporary file renamed into place; returns the
    path, or raises ImageIOError with one line."""
    path = os.fspath(path)
    write_files([path], lambda temp, target, _: _put(temp, target, data))
    return path


def _put(temp: str, target: str, data: bytes) -> None:
    try:
        with open(temp, "wb") as handle:
            handle.write(data)
    except OSError as exc:
        raise ImageIOError(f"cannot write {target}: {exc.strerror or exc}") from None


def write_images(temp: str, target: str, writes) -> None:
    """Open ``temp`` and write each (spec or list of specs, mode, data) in turn, every result
    checked; one-line errors naming ``target``, with what the libraries printed folded in
    (:mod:`envconv.io.chatter`)."""
    fmt = format_of(target)[0]
    with library_output(f"cannot write {target}", temp):
        if fmt in STREAMED and os.path.isdir("/dev/fd"):
            _write_streamed(temp, target, writes, fmt)
        else:
            _write_all(temp, target, writes)
        if fmt in CHECKED_AFTER:
            _check_whole(temp, target, fmt)


def _check_whole(temp: str, target: str, fmt: str) -> None:
    """Refuse a file of :data:`CHECKED_AFTER` whose end is not the format's, or that its
    reader will not open (OpenImageIO's TGA reader compares the header's image size with the
    file's): what a failed write the writer ignored leaves."""
    ending = CHECKED_AFTER[fmt]
    try:
        with open(temp, "rb") as handle:
            handle.seek(max(0, os.fstat(handle.fileno()).st_size - len(ending)))
            whole = handle.read() == ending
    except OSError as exc:
        raise ImageIOError(f"cannot write {target}: {exc.strerror or exc}") from None
    oiio = _oiio()
    inp = oiio.ImageInput.open(temp) if whole else None
    if inp is None:
        oiio.geterror()  # clear the reader's message
        raise ImageIOError(f"cannot write {target}: the file written is incomplete "
                           "(the disk full, or a file size limit)")  # fmt: skip
    inp.close()


def _write_streamed(temp: str, target: str, writes, fmt: str) -> None:
    """OpenImageIO encodes ``writes`` into a pipe; a thread copies it into ``temp`` and keeps
    the first OSError of a ``write`` or the ``close`` (then drains the rest unwritten, so the
    encoder never blocks nor sees a broken pipe)."""
    try:
        fd = os.open(temp, os.O_WRONLY | os.O_TRUNC | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise ImageIOError(f"cannot write {target}: {exc.strerror or exc}") from None
    read_end, write_end = os.pipe()
    failures: list[OSError] = []

    def copy() -> None:
        with os.fdopen(read_end, "rb", buffering=0) as pipe:
            while block := pipe.read(1 << 16):
                view = memoryview(block)
                while view and not failures:
                    try:
                        view = view[os.write(fd, view) :]
                    except OSError as exc:
                        failures.append(exc)
        try:
            os.close(fd)  # NFS reports a failed write here
        except OSError as exc:
            failures.append(exc)

    thread = threading.Thread(target=copy, name="envconv-write", daemon=True)
    thread.start()
    try:
        _write_all(f"/dev/fd/{write_end}", target, writes, fmt)
    finally:
        os.close(write_end)
        thread.join()
    if failures:
        raise ImageIOError(f"cannot write {target}: {failures[0].strerror or failures[0]}")


def _write_all(temp, target, writes, fmt: str | None = None) -> None:
    oiio = _oiio()
    out = oiio.ImageOutput.create(fmt or temp)
    if out is None:
        raise ImageIOError(f"cannot write {target}: {_first_line(oiio.geterror())}")
    try:
        for spec, mode, data in writes:
            opened = out.open(temp, spec) if isinstance(spec, list) else out.open(temp, spec, mode)
            if not opened:
                raise ImageIOError(f"cannot write {target}: {_error(out.geterror(), temp, target)}")
            if not _write_pixels(out, data):
                raise ImageIOError(f"cannot write {target}: {_error(out.geterror(), temp, target)}")
    finally:
        ok = out.close()
        message = out.geterror()
        del out  # release (and flush) the file before it is renamed into place
        if not ok:
            raise ImageIOError(f"cannot write {target}: {_error(message, temp, target)}")


def _error(message: str, temp: str, target: str) -> str:
    """The first line of a library's error, naming the target rather than its temp file."""
    return _first_line(message).replace(temp, target)


def _write_pixels(out, data) -> bool:
    """Write one image's pixels (H, W, C: an array or an :class:`envconv.io.encode.LazyLevel`)
    to the open ``out`` in bands of rows (scanline files) or of rows of tiles (tiled files);
    False on a write error (``out.geterror()``).

    Tiled files (MIP levels) go through ``write_tiles``, never ``write_image``: OpenImageIO's
    ``write_image`` hands the tiles of a tiled file to its thread pool and, when a write fails
    (a full disk: ENOSPC, EFBIG), waits forever for a task that has given up, with SIGINT
    ignored. ``write_tiles`` writes in this thread and returns False.
    """
    spec = out.spec()
    height = data.shape[0]
    lazy = hasattr(data, "rows")  # an encode.LazyLevel: encoded here, band by band
    rows = max(1, WRITE_BAND_BYTES // max(1, data.shape[1] * data.shape[2] * data.itemsize))
    rows = data.band_rows if lazy else rows
    if spec.tile_width:
        rows = max(spec.tile_height, rows // spec.tile_height * spec.tile_height)
    for y0 in range(0, height, rows):
        band = data.rows(y0, min(height, y0 + rows)) if lazy else data[y0 : y0 + rows]
        y1 = spec.y + y0 + band.shape[0]
        if spec.tile_width:
            done = out.write_tiles(spec.x, spec.x + spec.width, spec.y + y0, y1, spec.z,
                                   spec.z + max(spec.depth, 1), band)  # fmt: skip
        else:
            done = out.write_scanlines(spec.y + y0, y1, spec.z, band)
        if not done:
            return False
    return True
