"""The floor of a one shot: what reading and writing the files alone costs, with no conversion.

    python benchmarks/floor_oneshot.py IN.exr OUT.exr FACE COMPRESSION WRITER
    python benchmarks/floor_oneshot.py --each FACE COMPRESSION WRITER IN OUT [IN OUT ...]

Imports numpy and one image library, reads a float lat-long EXR, fills a vertical cross of
FACE × FACE cells (3 FACE wide, 4 FACE tall, half its cells empty, as envconv's cube-vcross)
with slices of the source, no resampling, and writes it as a float EXR with COMPRESSION
(``zip``, ``none``...). WRITER ``oiio`` reads and writes with OpenImageIO (as envconv writes
every file); ``openexr`` with the OpenEXR module's own public API on every core (as envconv
reads plain EXRs). Prints nothing. ``--each`` converts every pair in turn with one thread, as
a batch worker does (targets.py runs two such processes side by side for the batch's floor).

``benchmarks/targets.py`` runs it beside the one shot rows: any program that converts this
file must at least import these libraries, decode the input and encode the cross, so its time
over the peer's one shot bounds what the one-shot and batch ratios can reach on the machine.
"""

from __future__ import annotations

import os
import sys

import numpy as np

__all__ = ["main"]


def _cross(source: np.ndarray, face: int) -> np.ndarray:
    """A vertical cross (+Y, then −X +Z +X, then −Y, then −Z) of blends of neighbouring texels
    of ``source``: interpolated values, which zip compresses as little as a resampled cross."""
    cross = np.zeros((4 * face, 3 * face, source.shape[2]), np.float32)
    step = max(1, source.shape[0] // (2 * face))
    cells = [(0, 1), (1, 0), (1, 1), (1, 2), (2, 1), (3, 1)]
    for k, (row, col) in enumerate(cells):
        x0 = (k * source.shape[1]) // len(cells)
        near = source[: face * step : step, x0 : x0 + face * step : step]
        far = source[1 : face * step + 1 : step, x0 + 1 : x0 + face * step + 1 : step]
        h, w = min(near.shape[0], far.shape[0]), min(near.shape[1], far.shape[1])
        frac = ((np.arange(w, dtype=np.float32) * np.float32(0.618034)) % 1)[
            :, None
        ]  # as a bilinear tap's
        cell = cross[row * face : row * face + h, col * face : col * face + w]
        np.multiply(near[:h, :w], 1 - frac, out=cell)
        cell += frac * far[:h, :w]
    return cross


def _oiio(src: str, dst: str, face: int, compression: str, threads: int) -> None:
    import OpenImageIO as oiio

    oiio.attribute("threads", threads)
    oiio.attribute("exr_threads", threads)

    image = oiio.ImageInput.open(src)
    if image is None:
        sys.exit(f"cannot read {src}: {oiio.geterror()}")
    cross = _cross(image.read_image(0, 0, 0, 3, "float"), face)
    image.close()
    spec = oiio.ImageSpec(cross.shape[1], cross.shape[0], cross.shape[2], "float")
    spec.attribute("compression", compression)
    out = oiio.ImageOutput.create(dst)
    if out is None or not out.open(dst, spec) or not out.write_image(cross) or not out.close():
        sys.exit(f"cannot write {dst}: {oiio.geterror()}")


def _openexr(src: str, dst: str, face: int, compression: str, threads: int) -> None:
    import OpenEXR

    OpenEXR.set_global_thread_count(threads if threads > 1 else 0)
    with OpenEXR.File(src) as image:
        cross = _cross(image.channels()["RGB"].pixels.astype(np.float32, copy=False), face)
    codes = {"zip": OpenEXR.ZIP_COMPRESSION, "zips": OpenEXR.ZIPS_COMPRESSION,
             "none": OpenEXR.NO_COMPRESSION, "rle": OpenEXR.RLE_COMPRESSION,
             "piz": OpenEXR.PIZ_COMPRESSION}  # fmt: skip
    header = {"compression": codes[compression], "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": cross}) as image:
        image.write(dst)


def main(argv: list[str]) -> None:
    usage = "usage: floor_oneshot.py IN.exr OUT.exr FACE COMPRESSION oiio|openexr\n" \
            "       floor_oneshot.py --each FACE COMPRESSION oiio|openexr IN OUT [IN OUT ...]"  # fmt: skip
    if len(argv) == 6 and argv[1] != "--each":
        pairs, (face, compression, writer), threads = [argv[1:3]], argv[3:6], os.cpu_count() or 1
    elif len(argv) >= 7 and argv[1] == "--each" and len(argv) % 2 == 1:
        pairs, (face, compression, writer), threads = (
            list(zip(argv[5::2], argv[6::2], strict=True)),
            argv[2:5],
            1,
        )
    else:
        sys.exit(usage)
    if writer not in ("oiio", "openexr"):
        sys.exit(usage)
    for src, dst in pairs:
        (_oiio if writer == "oiio" else _openexr)(src, dst, int(face), compression, threads)


if __name__ == "__main__":
    main(sys.argv)
