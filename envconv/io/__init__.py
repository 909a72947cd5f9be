"""File I/O: the only package that opens image files and the only caller of OpenImageIO/OpenEXR.

Reading (:func:`read`) places a file's pixels in a layout and converts them to the working
space; writing (:func:`write`) stores a map in any format envconv writes, every MIP level and
face file, through a temporary file renamed into place. The modules:

* :mod:`~envconv.io.reader`: maps from files (one file, ``{face}`` sets, parts, levels);
* :mod:`~envconv.io.writer`: maps to files, and :func:`write_bytes` for made containers;
* :mod:`~envconv.io.write_plan`: what a write will store (files, pixel type, channels,
  levels), asked by the writer and by every plan before any pixel;
* :mod:`~envconv.io.output`: every file written: temporary files, each result checked;
* :mod:`~envconv.io.sets`: files replaced all at once (a journal), and read never half replaced;
* :mod:`~envconv.io.specs`: what a written image carries (channels, tags, its ImageSpec);
* :mod:`~envconv.io.temps`: the temporary files of writes (names, locks, stale ones);
* :mod:`~envconv.io.probe`: a map's facts from its headers alone (``envconv info``);
* :mod:`~envconv.io.files`: headers, display/data windows and parts, through OIIO;
* :mod:`~envconv.io.chatter`: what the image libraries print, captured and folded into errors;
* :mod:`~envconv.io.exr`: OpenEXR's own decoder for plain scanline EXR pixels;
* :mod:`~envconv.io.formats`: extensions, pixel types and compressions per format;
* :mod:`~envconv.io.encode`: the output plan (pixel type, colour space, clipping);
* :mod:`~envconv.io.face_files`: ``{face}`` paths of cube-face and skybox sets;
* :mod:`~envconv.io.textures`, :mod:`~envconv.io.dds`, :mod:`~envconv.io.ktx2`: engine
  containers, written and read; :mod:`~envconv.io.picture`: 8-bit pictures (previews, contact
  sheets).
"""

from __future__ import annotations

import importlib

__all__ = ["read", "read_unplaced", "read_header", "read_image", "read_pixel_type", "mip_levels",
           "probe", "Probe", "write", "write_bytes", "output_paths", "plan_write", "check_write", "WritePlan",
           "FORMATS", "WRITE_FORMATS", "COMPRESSIONS"]  # fmt: skip

# Where each public name lives. Loaded on first use, so importing one submodule (e.g.
# envconv.io.files for a header) does not import the readers, the writers and the layouts.
_HOMES = {
    **dict.fromkeys(("read", "read_unplaced", "read_header", "read_image", "read_pixel_type",
                     "mip_levels"), "reader"),
    **dict.fromkeys(("probe", "Probe"), "probe"),
    **dict.fromkeys(("write", "write_bytes"), "writer"),
    **dict.fromkeys(("output_paths", "plan_write", "check_write", "WritePlan"), "write_plan"),
    **dict.fromkeys(("FORMATS", "WRITE_FORMATS", "COMPRESSIONS"), "formats"),
}  # fmt: skip


def __getattr__(name: str):
    if name in _HOMES:
        value = getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
