"""Plain scanline EXR pixels: OpenImageIO alone against OIIO's header + OpenEXR's decoder.

Why envconv decodes plain EXRs with OpenEXR's Python API (``envconv/exr_io.py``) and writes
every file with OIIO. Both libraries through their public APIs only, in one process, each
library using every core; median of several runs after a warm-up. Run by hand:

    python benchmarks/exr_io.py
"""

from __future__ import annotations

import os
import statistics
import sys
import tempfile
import time

import numpy as np
import OpenEXR
import OpenImageIO as oiio

_COMPRESSIONS = {"zip": "ZIP_COMPRESSION", "none": "NO_COMPRESSION", "piz": "PIZ_COMPRESSION"}


def _median(fn, *args, runs: int = 9) -> float:
    fn(*args)
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn(*args)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _write_oiio(path: str, pixels: np.ndarray, pixel_type: str, compression: str) -> None:
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], pixel_type)
    spec.attribute("compression", compression)
    out = oiio.ImageOutput.create(path)
    if not (out.open(path, spec) and out.write_image(pixels) and out.close()):
        raise SystemExit(out.geterror())


def _write_openexr(path: str, pixels: np.ndarray, dtype, compression: str) -> None:
    header = {
        "compression": getattr(OpenEXR, _COMPRESSIONS[compression]),
        "type": OpenEXR.scanlineimage,
    }
    with OpenEXR.File(header, {"RGB": np.ascontiguousarray(pixels, dtype)}) as exr:
        exr.write(path)


def _read_oiio(path: str) -> np.ndarray:
    inp = oiio.ImageInput.open(path)
    pixels = inp.read_image(0, 0, 0, inp.spec().nchannels, oiio.FLOAT)
    inp.close()
    return pixels


def _read_openexr(path: str) -> np.ndarray:
    """As envconv reads: OIIO opens the file for its header, OpenEXR decodes the pixels."""
    inp = oiio.ImageInput.open(path)
    inp.spec()
    inp.close()
    with OpenEXR.File(path) as exr:
        return exr.channels()["RGB"].pixels.astype(np.float32, copy=False)


def main() -> None:
    cores = os.cpu_count() or 1
    OpenEXR.set_global_thread_count(cores)
    print(f"OpenImageIO {oiio.__version__}, OpenEXR {OpenEXR.__version__}, {cores} cores")
    rng = np.random.default_rng(1)
    with tempfile.TemporaryDirectory() as tmp:
        for height in (1024, 2048):
            pixels = rng.uniform(0, 50, (height, 2 * height, 3)).astype(np.float32)
            for pixel_type, dtype in (("float", np.float32), ("half", np.float16)):
                for compression in _COMPRESSIONS:
                    path = os.path.join(tmp, f"{height}-{pixel_type}-{compression}.exr")
                    _write_oiio(path, pixels, pixel_type, compression)
                    if not np.array_equal(_read_oiio(path), _read_openexr(path)):
                        raise SystemExit(f"the two readers disagree on {path}")
                    read = [_median(_read_oiio, path), _median(_read_openexr, path)]
                    written = [
                        _median(_write_oiio, path + ".o.exr", pixels, pixel_type, compression),
                        _median(_write_openexr, path + ".e.exr", pixels, dtype, compression),
                    ]
                    print(f"{2 * height}x{height} {pixel_type:5} {compression:4}: "
                          f"read OIIO {read[0] * 1e3:6.1f} ms, OIIO header + OpenEXR {read[1] * 1e3:6.1f} ms | "
                          f"write OIIO {written[0] * 1e3:6.1f} ms, OpenEXR {written[1] * 1e3:6.1f} ms")  # fmt: skip
    sys.stdout.flush()


if __name__ == "__main__":
    main()
