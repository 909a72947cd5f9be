"""Shared fixtures and helpers for the envconv test suite.

- ``tests/analytic.py``: radiance as a function of direction (the truth).
- ``tests/naive.py``: an independent numpy reading of docs/geometry.md and a slow resampler.
- Here: hypothesis settings, cached analytic sources, image writers that bypass envconv (for
  untagged files), a CLI runner and small metric helpers.
"""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest
from hypothesis import settings

sys.path.insert(0, os.path.dirname(__file__))

import analytic  # noqa: E402
import naive  # noqa: E402

__all__ = [
    "rel_rms",
    "write_plain",
    "file_state",
    "run_cli",
    "stderr_lines",
    "detect_layout",
    "sh_evaluate",
]

# 100 random points per property and layout (17 layouts, two properties in test_layouts.py;
# the pixel-centre grid tests there cover every pixel besides): 200 took 12.8 s of the suite.
settings.register_profile("envconv", max_examples=100, deadline=None)
settings.load_profile("envconv")


def rel_rms(result, truth, weights=None) -> float:
    """Relative RMS error ‖result − truth‖ / ‖truth‖, optionally weighted per pixel (H, W)."""
    result = np.asarray(result, np.float64)
    truth = np.asarray(truth, np.float64)
    if weights is None:
        weights = np.ones(truth.shape[:2])
    w = np.asarray(weights, np.float64)[..., None]
    return float(np.sqrt((w * (result - truth) ** 2).sum() / (w * truth**2).sum()))


def detect_layout(width, height, metadata, pixels=None):
    """(layout, guard) the reader would place an image in (envconv.layouts.detect.find_layout),
    or the LayoutError it would raise, asking for --from."""
    from envconv.errors import LayoutError
    from envconv.layouts.detect import find_layout

    found = find_layout(width, height, metadata, pixels)
    if found.layout is None:
        raise LayoutError(found.reason)
    return found.layout, found.guard


def sh_evaluate(coefficients, dirs, frame: str = "world") -> np.ndarray:
    """Σ c_lm Y_lm(d) at unit directions (..., 3): (..., C), with envconv's SH basis; with
    irradiance coefficients this is the irradiance E(n)."""
    from envconv.resample.harmonics import sh_basis

    return sh_basis(dirs, frame) @ np.asarray(coefficients, np.float64)


def write_plain(path, pixels, attributes=None, pixel_type="float") -> None:
    """Write an image with OpenImageIO directly: no envconv layout tag (for detection tests)."""
    import OpenImageIO as oiio

    pixels = np.ascontiguousarray(pixels, np.float32)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    height, width, nch = pixels.shape
    spec = oiio.ImageSpec(width, height, nch, getattr(oiio, pixel_type.upper()))
    for name, value in (attributes or {}).items():
        spec.attribute(name, value)
    out = oiio.ImageOutput.create(str(path))
    assert out is not None, oiio.geterror()
    assert out.open(str(path), spec), out.geterror()
    assert out.write_image(pixels), out.geterror()
    assert out.close()


def file_state(path) -> tuple[int, bytes]:
    """(mtime in ns, bytes) of a file, to prove it was not touched."""
    with open(path, "rb") as handle:
        data = handle.read()
    return os.stat(path).st_mtime_ns, data


def run_cli(args):
    """Invoke the envconv click group in-process; returns click's Result (stdout, stderr split)."""
    from click.testing import CliRunner

    from envconv.cli import convert, info, layouts  # noqa: F401  (registers the commands)
    from envconv.cli.main import cli

    return CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)


def stderr_lines(result) -> list[str]:
    """Non-empty lines a CLI run printed on stderr."""
    return [line for line in result.stderr.splitlines() if line.strip()]


@pytest.fixture(scope="session")
def latlong_truth():
    """Analytic pixel averages of :func:`analytic.radiance` on a 128×64 lat-long (float64)."""
    return naive.pixel_average("latlong", 64, analytic.radiance, samples=8)


@pytest.fixture(scope="session")
def latlong_source(latlong_truth):
    """The same as an EnvMap."""
    import envconv

    return envconv.EnvMap(latlong_truth.astype(np.float32), "latlong")


@pytest.fixture(scope="session")
def smooth_truth():
    """Analytic pixel averages of :func:`analytic.smooth_radiance`, 128×64 lat-long."""
    return naive.pixel_average("latlong", 64, analytic.smooth_radiance, samples=8)
