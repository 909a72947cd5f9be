"""ffmpeg's v360 filter as a peer: the same lat-long in, its picture out, compared with envconv's.

ffmpeg clips to integers, so the source is a smooth pattern in [0, 1] stored as a 16-bit PNG
(``rgb48``, which v360 filters as ``gbrp16`` without any colour conversion) and its output is
read back as 16-bit. envconv resamples the very same 16-bit values (as floats, no colour
transform), one bilinear tap per pixel as ffmpeg does (``samples=1``).

ffmpeg 5.1 (Debian 12) reads an equirectangular input with its first and last columns on the
seam (``xyz_to_equirect``: ``(φ/π + 1)/2 · (W − 1)``), half a source pixel from the pixel-centre
rule at the seam; a 1024-pixel-wide source keeps that under a tenth of an output pixel here.

The comparison must tell a correct layout from a wrong one: :func:`discriminates` checks that
the peer's picture is far further from pictures with a half-pixel shift, a mirrored face or a
rotated face (made from the pattern itself, evaluated at the shifted or turned pixel centres)
than from envconv's.
"""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

__all__ = ["FFMPEG", "need_ffmpeg", "pattern", "write_rgb16", "read_rgb16", "v360", "rms",
           "discriminates", "pattern_latlong"]  # fmt: skip

FFMPEG = shutil.which("ffmpeg")


def need_ffmpeg() -> str:
    """The ffmpeg executable, or skip (CI installs it: .ci/run)."""
    if FFMPEG is None:
        pytest.skip("ffmpeg is not installed (apt-get install ffmpeg); .ci/run installs it")
    return FFMPEG


def pattern(dirs: np.ndarray) -> np.ndarray:
    """A smooth RGB pattern in [0.05, 0.95] that changes along every direction: each channel
    mixes the three components differently, so no mirror or turn of a face leaves it alone."""
    x, y, z = dirs[..., 0], dirs[..., 1], dirs[..., 2]
    red = 0.5 + 0.45 * x
    green = 0.5 + 0.3 * y + 0.15 * z
    blue = 0.5 + 0.25 * z + 0.2 * x * y
    return np.stack([red, green, blue], -1)


def write_rgb16(path, pixels: np.ndarray) -> np.ndarray:
    """Write ``pixels`` in [0, 1] as a 16-bit RGB PNG with OpenImageIO directly (no envconv,
    no colour transform); returns the stored values as float32."""
    import OpenImageIO as oiio

    stored = np.round(np.clip(pixels, 0.0, 1.0) * 65535).astype(np.uint16)
    height, width = stored.shape[:2]
    out = oiio.ImageOutput.create(str(path))
    assert out is not None, oiio.geterror()
    assert out.open(str(path), oiio.ImageSpec(width, height, 3, oiio.UINT16)), out.geterror()
    assert out.write_image(stored), out.geterror()
    assert out.close()
    return stored.astype(np.float32) / 65535


def read_rgb16(path) -> np.ndarray:
    """A 16-bit PNG's pixels as float64 in [0, 1]."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    pixels = inp.read_image(oiio.UINT16)
    inp.close()
    return np.asarray(pixels, np.float64) / 65535


def v360(source_png, out_png, options: str) -> np.ndarray:
    """Run ``ffmpeg -vf v360=OPTIONS`` on ``source_png`` into a 16-bit PNG; its pixels."""
    command = [need_ffmpeg(), "-nostdin", "-y", "-loglevel", "error", "-i", str(source_png),
               "-vf", f"v360={options}", "-pix_fmt", "rgb48le", str(out_png)]  # fmt: skip
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return read_rgb16(out_png)


def rms(a, b, mask=None) -> float:
    """RMS difference of two pictures (over ``mask``'s pixels when given)."""
    diff = (np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2
    if mask is not None:
        diff = diff[mask]
    return float(np.sqrt(diff.mean()))


def discriminates(peer, ours, wrong: dict[str, np.ndarray], factor: float = 4.0, mask=None):
    """Assert that ``peer`` is at least ``factor`` times further from every ``wrong`` picture
    (name → picture) than from ``ours``; returns the distances, for messages."""
    near = rms(peer, ours, mask)
    far = {name: rms(peer, picture, mask) for name, picture in wrong.items()}
    for name, distance in far.items():
        assert distance > factor * near, (name, distance, near)
    return near, far


def pattern_latlong(folder, height: int = 512):
    """(path, EnvMap): the pattern as a ``2·height × height`` lat-long, written as a 16-bit PNG
    in ``folder``, and the same stored values as an envconv map."""
    import envconv
    from envconv.layouts.geometry import pixel_directions

    dirs, _ = pixel_directions("latlong", height)
    path = folder / "pattern-latlong.png"
    stored = write_rgb16(path, pattern(dirs))
    return path, envconv.EnvMap(stored, "latlong")
