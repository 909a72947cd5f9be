"""``envconv info`` and ``envconv layouts``."""

from __future__ import annotations

import json

import analytic
import naive
import numpy as np
import pytest
from conftest import run_cli, stderr_lines, write_plain

import envconv
from envconv.layouts import LAYOUTS


def test_layouts_lists_every_layout_with_a_description():
    result = run_cli(["layouts"])
    assert result.exit_code == 0
    block = result.stdout.split("\n\n")[0]  # then the skybox face sets (test_facesets.py)
    lines = [line for line in block.splitlines() if line.strip()]
    assert len(lines) == len(LAYOUTS)
    for line, name in zip(lines, LAYOUTS, strict=True):
        first, _, rest = line.partition(" ")
        assert first == name
        assert len(rest.strip()) > 10


@pytest.mark.parametrize("name, n", [("latlong", 64), ("cube-vcross", 24), ("sphere", 48),
                                     ("tennisball", 24)])  # fmt: skip
def test_info_json_reports_the_map(tmp_path, name, n):
    pixels = naive.pixel_average(name, n, analytic.radiance, 6)
    path = tmp_path / "map.exr"
    envconv.write(envconv.EnvMap(pixels, name), path, bit_depth="float")
    result = run_cli(["info", path, "--json"])
    assert result.exit_code == 0, result.stderr
    record = json.loads(result.stdout)
    height, width = pixels.shape[:2]
    assert record["layout"] == name
    assert record["size"] == n
    assert (record["width"], record["height"]) == (width, height)
    assert record["channels"] == ["R", "G", "B"]
    np.testing.assert_allclose(record["min"], pixels.min((0, 1)), rtol=1e-6)
    np.testing.assert_allclose(record["max"], pixels.max((0, 1)), rtol=1e-6)
    mean = np.asarray(record["mean_radiance"])
    if name == "tennisball":
        # The bands overlap (CONVENTIONS.md), so every pixel counts once and the overlap twice;
        # that mean is the analytic mean over the two bands, computed here by supersampling.
        omega = naive.pixel_solid_angles(name, n, 8)
        expected = (pixels * omega[..., None]).sum((0, 1)) / omega.sum()
    else:
        expected = analytic.sphere_mean(analytic.radiance)
    np.testing.assert_allclose(mean, expected, rtol=5e-3)


def test_info_text_mode(tmp_path):
    path = tmp_path / "m.exr"
    envconv.write(envconv.EnvMap(np.full((8, 16, 3), 2.0), "latlong"), path)
    result = run_cli(["info", path])
    assert result.exit_code == 0, result.stderr
    assert "layout: latlong" in result.stdout
    assert "size: 8" in result.stdout


def test_info_needs_from_for_an_untagged_square(tmp_path):
    path = tmp_path / "square.exr"
    write_plain(path, np.ones((16, 16, 3)))
    result = run_cli(["info", path, "--json"])
    assert result.exit_code != 0
    assert len(stderr_lines(result)) == 1
    assert "sphere" in result.stderr and "angular" in result.stderr
    result = run_cli(["info", path, "--json", "--from", "sphere"])
    assert result.exit_code == 0, result.stderr
    record = json.loads(result.stdout)
    assert record["layout"] == "sphere"
    np.testing.assert_allclose(record["mean_radiance"], [1.0, 1.0, 1.0], rtol=1e-6)


@pytest.mark.parametrize("content", [None, b"garbage bytes, not an EXR\n" * 8])
def test_info_errors_are_one_line(tmp_path, content):
    path = tmp_path / "bad.exr"
    if content is not None:
        path.write_bytes(content)
    result = run_cli(["info", path])
    assert result.exit_code != 0
    assert len(stderr_lines(result)) == 1, result.stderr
    assert "Traceback" not in result.output
