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
    result = run_cli(["info", path, "--json", "--stats"])
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
        # The bands overlap (docs/geometry.md), so every pixel counts once and the overlap twice;
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


def test_info_reports_an_untagged_square_as_unknown_until_from(tmp_path):
    """1:1 could be sphere, angular or one of the octahedral squares: info still answers,
    with layout "unknown", the candidates and why; --from places it."""
    path = tmp_path / "square.exr"
    write_plain(path, np.ones((16, 16, 3)))
    result = run_cli(["info", path, "--json", "--stats"])
    assert result.exit_code == 0, result.stderr
    record = json.loads(result.stdout)
    assert record["layout"] == "unknown" and record["candidates"] == [
        "sphere",
        "angular",
        "octahedral",
        "equal-area",
        "fisheye",
    ]
    assert "sphere, angular" in record["reason"] and "--from" in record["reason"]
    assert (record["width"], record["height"], record["size"], record["mean_radiance"]) == (
        16,
        16,
        None,
        None,
    )
    result = run_cli(["info", path, "--json", "--from", "sphere", "--stats"])
    assert result.exit_code == 0, result.stderr
    record = json.loads(result.stdout)
    assert record["layout"] == "sphere"
    np.testing.assert_allclose(record["mean_radiance"], [1.0, 1.0, 1.0], rtol=1e-6)


def _oiio_file(path, pixels, names, pixel_type="half", display=None, data=None, attributes=None):
    """An image written by OIIO directly, windows as (x, y, w, h)."""
    import OpenImageIO as oiio

    height, width, nch = pixels.shape
    spec = oiio.ImageSpec(width, height, nch, getattr(oiio, pixel_type.upper()))
    spec.channelnames = tuple(names)
    if data is not None:
        spec.x, spec.y = data[:2]
        spec.full_x, spec.full_y, spec.full_width, spec.full_height = display
    for name, value in (attributes or {}).items():
        spec.attribute(name, value)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec) and out.write_image(pixels) and out.close()


def test_info_describes_a_photograph_no_layout_fits(tmp_path):
    """Like OpenEXR's sample GoldenGate.exr (1262x860 RGBA half): not an environment, yet
    info gives its size, windows, channels and types, parts, colour space, range and
    metadata, in JSON and as text, and says why it has no layout."""
    rng = np.random.default_rng(2)
    pixels = rng.uniform(0, 4, (860, 1262, 4)).astype(np.float16).astype(np.float32)
    path = tmp_path / "GoldenGate.exr"
    _oiio_file(
        path, pixels, "RGBA", attributes={"owner": "ILM", "oiio:ColorSpace": "lin_rec709_scene"}
    )
    result = run_cli(["info", path, "--json", "--stats"])
    assert result.exit_code == 0, result.stderr
    record = json.loads(result.stdout)
    assert record["layout"] == "unknown" and record["candidates"] == []
    assert "1262x860" in record["reason"] and "matches no layout's aspect" in record["reason"]
    assert (record["width"], record["height"]) == (1262, 860)
    assert record["display_window"] == record["data_window"] == [0, 0, 1262, 860]
    assert record["channels"] == ["R", "G", "B", "A"] and record["channel_types"] == ["half"] * 4
    assert record["pixel_type"] == "half" and record["levels"] == [[1262, 860]]
    assert [(p["name"], p["read"], p["channels"]) for p in record["parts"]] == [
        ("", True, ["R", "G", "B", "A"])
    ]
    assert record["colorspace"] == "Linear Rec.709 (sRGB)"
    np.testing.assert_allclose(record["min"], pixels.min((0, 1)))
    np.testing.assert_allclose(record["max"], pixels.max((0, 1)))
    assert record["nonfinite"] == 0 and record["metadata"]["Copyright"] == "ILM"
    assert record["size"] is None and record["guard"] is None and record["mean_radiance"] is None
    text = run_cli(["info", path])
    assert text.exit_code == 0, text.stderr
    assert "layout: unknown" in text.stdout and "width: 1262" in text.stdout
    assert "matches no layout's aspect" in text.stdout


def test_info_reports_both_windows_of_an_image_with_holes(tmp_path):
    """Like OpenEXR's samples whose data window is smaller than the display window: the
    image is the display window, the held pixels where the data window puts them, an A that
    the file does not store (type None) says which those are."""
    pixels = np.full((50, 60, 3), 2.0, np.float32)
    path = tmp_path / "window.exr"
    _oiio_file(path, pixels, "RGB", "float", display=(0, 0, 100, 80), data=(10, 5, 60, 50))
    record = json.loads(run_cli(["info", path, "--json", "--stats"]).stdout)
    assert record["layout"] == "unknown"
    assert (record["width"], record["height"]) == (100, 80)
    assert record["display_window"] == [0, 0, 100, 80] and record["data_window"] == [10, 5, 60, 50]
    assert record["channels"] == ["R", "G", "B", "A"]
    assert record["channel_types"] == ["float", "float", "float", None]
    assert record["min"] == [0.0, 0.0, 0.0, 0.0] and record["max"] == [2.0, 2.0, 2.0, 1.0]


def test_info_with_a_from_the_size_does_not_fit_says_which_sizes_would(tmp_path):
    path = tmp_path / "odd.exr"
    write_plain(path, np.ones((81, 100, 3)))
    result = run_cli(["info", path, "--from", "latlong"])
    assert result.exit_code == 1
    (line,) = stderr_lines(result)
    assert "latlong (given by --from) needs width = 2 × height, and 100x81 is not" in line
    assert "162x81" in line and "100x50" in line


@pytest.mark.parametrize("content", [None, b"garbage bytes, not an EXR\n" * 8])
def test_info_errors_are_one_line(tmp_path, content):
    path = tmp_path / "bad.exr"
    if content is not None:
        path.write_bytes(content)
    result = run_cli(["info", path])
    assert result.exit_code != 0
    assert len(stderr_lines(result)) == 1, result.stderr
    assert "Traceback" not in result.output


def test_info_reads_headers_only_unless_stats(tmp_path):
    """A file whose header is whole but whose pixels are cut off: without --stats info
    describes it from the header (so it cannot have read the pixels), with --stats the
    pixel read fails with one line."""
    path = tmp_path / "cut.exr"
    noise = np.random.default_rng(1).uniform(0, 1, (32, 64, 3))  # does not compress away
    write_plain(path, noise, attributes={"compression": "zip", "owner": "me"})
    data = path.read_bytes()
    path.write_bytes(data[: len(data) * 2 // 3])
    result = run_cli(["info", path, "--json"])
    assert result.exit_code == 0, result.stderr
    record = json.loads(result.stdout)
    assert (record["layout"], record["size"], record["width"], record["height"]) == (
        "latlong",
        32,
        64,
        32,
    )
    assert record["metadata"]["Copyright"] == "me"
    assert not {"min", "max", "nonfinite", "mean_radiance"} & set(record)
    stats = run_cli(["info", path, "--json", "--stats"])
    assert stats.exit_code == 1 and stats.stdout == ""
    assert len(stderr_lines(stats)) == 1 and "cut.exr" in stats.stderr


def test_info_on_a_face_set_reports_the_files_colour_space_and_metadata(tmp_path):
    """Six sRGB PNG faces: info says sRGB and shows the files' own metadata (not the
    working space's tag the read gives the map), and --stats reads all six."""
    for k, face in enumerate(("px", "nx", "py", "ny", "pz", "nz")):
        pixels = np.full((8, 8, 3), 40 * k, np.uint8)
        _oiio_file(tmp_path / f"sky_{face}.png", pixels, "RGB", "uint8",
                   attributes={"oiio:ColorSpace": "srgb_rec709_scene", "Artist": "someone"})  # fmt: skip
    template = str(tmp_path / "sky_{face}.png")
    record = json.loads(run_cli(["info", template, "--json"]).stdout)
    assert (record["layout"], record["size"], record["width"], record["height"]) == (
        "cube-faces",
        8,
        48,
        8,
    )
    assert record["colorspace"].startswith("sRGB")
    assert record["metadata"]["oiio:ColorSpace"] == "srgb_rec709_scene"
    assert record["metadata"]["Artist"] == "someone"
    stats = json.loads(run_cli(["info", template, "--json", "--stats"]).stdout)
    assert stats["min"] == [0.0] * 3  # face px holds code 0, nz code 200: sRGB-decoded
    expected = ((200 / 255 + 0.055) / 1.055) ** 2.4
    np.testing.assert_allclose(stats["max"], [expected] * 3, rtol=1e-3)
