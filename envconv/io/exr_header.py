"""``oiio:sampleborder = 0`` in the header of an OpenEXR environment map envconv writes.

OpenImageIO's OpenEXR reader reports ``oiio:sampleborder = 1`` for every file with an
``envmap`` attribute, after OpenEXR's ``ImfEnvmap``, whose samples lie on the image's edges;
its TextureSystem then places the samples of envconv's lat-longs (pixel centres) up to half a
row off. An ``oiio:sampleborder`` attribute stored in the header wins over that default
(the reader copies the header's attributes after setting it), and 0 tells OIIO the samples
are centred. OIIO's writer, though, drops every ``oiio:`` attribute but three, so envconv
writes an int attribute of the same length, :data:`PLACEHOLDER`, and renames it in the
written file (:func:`store_sampleborder`) before the file is renamed into place.

The header is OpenEXR's documented layout: the magic number, a version word, then for each
part a list of attributes (name, NUL, type name, NUL, 4-byte little-endian size, value) that
ends with a NUL byte; a multi-part file's list of headers ends with an empty header. The
rename writes 17 bytes over 17 bytes, so no offset in the file moves.
"""

from __future__ import annotations

import struct

from ..errors import ImageIOError

__all__ = ["PLACEHOLDER", "SAMPLEBORDER", "store_sampleborder"]

#: The attribute OIIO reads, and the name envconv has OIIO write in its place.
SAMPLEBORDER = b"oiio:sampleborder"
PLACEHOLDER = SAMPLEBORDER.replace(b":", b"_").decode()

_MAGIC = b"\x76\x2f\x31\x01"
_MULTIPART = 0x1000
#: Header bytes read at most; envconv's headers are a few kilobytes.
_HEADER_LIMIT = 1 << 24


def _placeholder_offsets(head: bytes) -> list[int]:
    """File offsets of every ``PLACEHOLDER`` int attribute's name in the header(s) ``head``."""
    if head[:4] != _MAGIC or len(head) < 9:
        raise ValueError("not an OpenEXR file")
    multipart = bool(struct.unpack_from("<I", head, 4)[0] & _MULTIPART)
    name, found, pos = PLACEHOLDER.encode(), [], 8
    while True:
        if head[pos] == 0:  # the end of one header
            pos += 1
            if not multipart or head[pos] == 0:
                return found
            continue
        name_end = head.index(b"\0", pos)
        type_end = head.index(b"\0", name_end + 1)
        (size,) = struct.unpack_from("<i", head, type_end + 1)
        if head[pos:name_end] == name and head[name_end + 1 : type_end] == b"int" and size == 4:
            found.append(pos)
        pos = type_end + 5 + size


def store_sampleborder(path: str, target: str) -> int:
    """Rename every :data:`PLACEHOLDER` attribute of the OpenEXR file ``path`` (written for
    ``target``) to ``oiio:sampleborder``; returns how many. Raises ImageIOError with one line
    when the header cannot be read or written, or holds no placeholder."""
    try:
        with open(path, "r+b") as handle:
            head = handle.read(_HEADER_LIMIT)
            try:
                offsets = _placeholder_offsets(head)
            except (ValueError, IndexError, struct.error):
                offsets = []
            for offset in offsets:
                handle.seek(offset)
                if handle.write(SAMPLEBORDER) != len(SAMPLEBORDER):
                    raise OSError("short write")
    except OSError as exc:
        raise ImageIOError(f"cannot write {target}: {exc.strerror or exc}") from None
    if not offsets:
        raise ImageIOError(f"cannot write {target}: its OpenEXR header has no {PLACEHOLDER} "
                           "attribute to store as oiio:sampleborder")  # fmt: skip
    return len(offsets)
