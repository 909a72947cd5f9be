"""The peer one shot for benchmarks/targets.py: py360convert + OpenCV, read and written with OIIO.

Runs in a venv of its own (no envconv in it)::

    python -m venv /work/venv-py360
    /work/venv-py360/bin/pip install py360convert opencv-python-headless OpenImageIO numpy
    /work/venv-py360/bin/python benchmarks/peer_py360.py IN.exr OUT.exr 512 zip

Reads a float lat-long EXR as float32, converts it with ``py360convert.e2c`` (bilinear, one tap
per pixel; py360convert uses OpenCV's ``remap`` when cv2 is installed) into a ``dice`` cross of
faces FACE × FACE (a horizontal cross: the same pixel count as envconv's cube-vcross), and writes
it as a float EXR with the given compression (``zip``, ``none``...). Prints nothing.
"""

from __future__ import annotations

import sys

import numpy as np
import OpenImageIO as oiio
import py360convert

__all__ = ["main"]


def main(argv: list[str]) -> None:
    if len(argv) != 5:
        sys.exit("usage: peer_py360.py IN.exr OUT.exr FACE COMPRESSION")
    src, dst, face, compression = argv[1], argv[2], int(argv[3]), argv[4]
    image = oiio.ImageInput.open(src)
    if image is None:
        sys.exit(f"cannot read {src}: {oiio.geterror()}")
    pixels = image.read_image(0, 0, 0, 3, "float")
    image.close()
    cross = np.ascontiguousarray(
        py360convert.e2c(pixels, face_w=face, mode="bilinear", cube_format="dice")
    )
    spec = oiio.ImageSpec(cross.shape[1], cross.shape[0], cross.shape[2], "float")
    spec.attribute("compression", compression)
    out = oiio.ImageOutput.create(dst)
    if out is None or not out.open(dst, spec) or not out.write_image(cross) or not out.close():
        sys.exit(f"cannot write {dst}: {oiio.geterror()}")


if __name__ == "__main__":
    main(sys.argv)
