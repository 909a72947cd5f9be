"""Multi-part OpenEXR files: every part of one environment converted, part names kept.

Files are crafted with OIIO and outputs read back with the OpenEXR library (an independent
reader). The truth for each part is the conversion of the same pixels stored as a single-part
file of their own.
"""

from __future__ import annotations

import os

import analytic
import naive
import numpy as np
import pytest
from conftest import run_cli, stderr_lines

import envconv


def write_parts(path, parts, pixel_type="half"):
    """A multi-part EXR written with OIIO: ``parts`` is [(name, channel names, pixels, data
    window or None)], all in a 64 x 32 display window."""
    import OpenImageIO as oiio

    specs = []
    for name, names, pixels, data in parts:
        height, width, nch = pixels.shape
        spec = oiio.ImageSpec(width, height, nch, getattr(oiio, pixel_type.upper()))
        spec.channelnames = tuple(names)
        spec.attribute("name", name)
        if data is not None:
            spec.x, spec.y = data[:2]
            spec.full_x, spec.full_y, spec.full_width, spec.full_height = 0, 0, 64, 32
        specs.append(spec)
    out = oiio.ImageOutput.create(os.fspath(path))
    assert out.open(os.fspath(path), specs), out.geterror()
    for k, (_, _, pixels, _) in enumerate(parts):
        if k:
            assert out.open(os.fspath(path), specs[k], "AppendSubimage"), out.geterror()
        assert out.write_image(np.ascontiguousarray(pixels, np.float32)), out.geterror()
    assert out.close()


def openexr_parts(path):
    """{part name: {channel: pixels}} as the OpenEXR library reads ``path``."""
    import OpenEXR

    with OpenEXR.File(os.fspath(path), separate_channels=True) as exr:
        return {part.name(): {c: ch.pixels.astype(np.float32) for c, ch in part.channels.items()}
                for part in exr.parts}  # fmt: skip


@pytest.fixture(scope="module")
def beauty_and_aov():
    sky = naive.pixel_average("latlong", 32, analytic.radiance, 4).astype(np.float32)
    rgba = np.concatenate([sky, np.ones((32, 64, 1), np.float32)], axis=2)
    aov = (sky[:, :, ::-1] * 0.5).astype(np.float32)  # a different image of the same world
    return rgba, aov


def _single(path, pixels, names):
    write_parts(path, [("only", names, pixels, None)])


def test_every_part_of_one_environment_is_converted_and_keeps_its_name(tmp_path, beauty_and_aov):
    rgba, aov = beauty_and_aov
    write_parts(tmp_path / "multi.exr", [("beauty", "RGBA", rgba, None),
                                         ("diffuse", ("diffuse.R", "diffuse.G", "diffuse.B"), aov, None)])  # fmt: skip
    env = envconv.read(tmp_path / "multi.exr")
    assert env.channels == ("R", "G", "B", "A", "diffuse.R", "diffuse.G", "diffuse.B")
    assert env.parts == (
        ("beauty", ("R", "G", "B", "A")),
        ("diffuse", ("diffuse.R", "diffuse.G", "diffuse.B")),
    )
    common = ["--to", "cube-vcross", "--size", "16", "--bit-depth", "float"]
    result = run_cli(["convert", tmp_path / "multi.exr", tmp_path / "out.exr", *common])
    assert result.exit_code == 0, result.stderr
    _single(tmp_path / "b.exr", rgba, "RGBA")
    _single(tmp_path / "d.exr", aov, ("diffuse.R", "diffuse.G", "diffuse.B"))
    for name in ("b", "d"):
        assert (
            run_cli(
                ["convert", tmp_path / f"{name}.exr", tmp_path / f"{name}-out.exr", *common]
            ).exit_code
            == 0
        )
    written = openexr_parts(tmp_path / "out.exr")
    assert list(written) == ["beauty", "diffuse"]
    beauty, diffuse = (next(iter(openexr_parts(tmp_path / f"{n}-out.exr").values())) for n in "bd")
    assert sorted(written["beauty"]) == sorted(beauty) and sorted(written["diffuse"]) == sorted(
        diffuse
    )
    for got, want in ((written["beauty"], beauty), (written["diffuse"], diffuse)):
        for channel in want:
            np.testing.assert_allclose(got[channel], want[channel], rtol=1e-6, atol=1e-7)
    back = envconv.read(tmp_path / "out.exr")
    assert back.parts == env.parts and back.layout.name == "cube-vcross"


def test_plain_channel_names_in_later_parts_are_prefixed_and_written_back_plain(
    tmp_path, beauty_and_aov
):
    rgba, aov = beauty_and_aov
    write_parts(
        tmp_path / "multi.exr", [("beauty", "RGBA", rgba, None), ("spec", "RGB", aov, None)]
    )
    env = envconv.read(tmp_path / "multi.exr")
    assert env.channels == ("R", "G", "B", "A", "spec.R", "spec.G", "spec.B")
    envconv.write(env, tmp_path / "out.exr", bit_depth="half")
    written = openexr_parts(tmp_path / "out.exr")
    assert sorted(written["spec"]) == ["B", "G", "R"]
    np.testing.assert_array_equal(
        written["spec"]["G"], aov[:, :, 1].astype(np.float16).astype(np.float32)
    )


def test_part_picks_one_part(tmp_path, beauty_and_aov):
    rgba, aov = beauty_and_aov
    write_parts(
        tmp_path / "multi.exr", [("beauty", "RGBA", rgba, None), ("diffuse", "RGB", aov, None)]
    )
    env = envconv.read(tmp_path / "multi.exr", part="diffuse")
    assert env.channels == ("R", "G", "B") and env.parts == ()
    np.testing.assert_array_equal(env.pixels, aov.astype(np.float16).astype(np.float32))
    assert envconv.read(tmp_path / "multi.exr", part="1").channels == ("R", "G", "B")
    result = run_cli(["convert", tmp_path / "multi.exr", tmp_path / "d.png", "--to", "latlong",
                      "--part", "diffuse"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    result = run_cli(["convert", tmp_path / "multi.exr", tmp_path / "x.exr", "--to", "latlong",
                      "--part", "specular"])  # fmt: skip
    assert result.exit_code == 1
    (line,) = stderr_lines(result)
    assert "no part 'specular'" in line and "beauty, diffuse" in line


def test_parts_of_other_windows_are_left_out_with_a_warning(tmp_path, beauty_and_aov, caplog):
    rgba, aov = beauty_and_aov
    write_parts(tmp_path / "multi.exr", [("beauty", "RGBA", rgba, None),
                                         ("crop", "RGB", aov[:16], (0, 0, 64, 16))])  # fmt: skip
    result = run_cli(["convert", tmp_path / "multi.exr", tmp_path / "out.exr", "--to", "latlong"])
    assert result.exit_code == 0, result.stderr
    (warning,) = [r.getMessage() for r in caplog.records if r.levelname.lower() == "warning"]
    assert "part crop is not read" in warning and "windows differ" in warning
    assert len(openexr_parts(tmp_path / "out.exr")) == 1
    crop = envconv.read(tmp_path / "multi.exr", part="crop")
    assert crop.channels == ("R", "G", "B", "A")  # its own holes
    np.testing.assert_array_equal(crop.pixels[16:], 0)


def test_info_lists_the_parts_and_which_are_read(tmp_path, beauty_and_aov):
    """Like OpenEXR's multi-part samples: each part's name, channels, types and windows."""
    import json

    rgba, aov = beauty_and_aov
    write_parts(tmp_path / "multi.exr", [("beauty", "RGBA", rgba, None), ("diffuse", "RGB", aov, None),
                                         ("crop", "RGB", aov[:16], (0, 0, 64, 16))])  # fmt: skip
    result = run_cli(["info", tmp_path / "multi.exr", "--json"])
    assert result.exit_code == 0, result.stderr
    record = json.loads(result.stdout)
    assert record["layout"] == "latlong"
    assert [(p["name"], p["read"]) for p in record["parts"]] == [
        ("beauty", True),
        ("diffuse", True),
        ("crop", False),
    ]
    assert "windows differ" in record["parts"][2]["why"]
    assert record["parts"][2]["data_window"] == [0, 0, 64, 16]
    assert record["channels"] == ["R", "G", "B", "A", "diffuse.R", "diffuse.G", "diffuse.B"]
    assert record["channel_types"] == ["half"] * 7


def test_holes_in_a_multi_part_file_give_the_first_part_an_alpha(tmp_path, beauty_and_aov):
    rgba, aov = beauty_and_aov
    write_parts(tmp_path / "top.exr", [("beauty", "RGB", rgba[:16, :, :3], (0, 0, 64, 16)),
                                       ("diffuse", "RGB", aov[:16], (0, 0, 64, 16))])  # fmt: skip
    env = envconv.read(tmp_path / "top.exr")
    assert env.parts == (("beauty", ("R", "G", "B", "A")), ("diffuse", ("R", "G", "B")))
    assert run_cli(["convert", tmp_path / "top.exr", tmp_path / "out.exr", "--to", "cube-vcross",
                    "--size", "8"]).exit_code == 0  # fmt: skip
    written = openexr_parts(tmp_path / "out.exr")
    assert sorted(written["beauty"]) == ["A", "B", "G", "R"] and sorted(written["diffuse"]) == [
        "B",
        "G",
        "R",
    ]


def test_alpha_added_by_resampling_joins_the_first_part(tmp_path, beauty_and_aov):
    rgba, aov = beauty_and_aov
    write_parts(
        tmp_path / "multi.exr",
        [("beauty", "RGB", rgba[:, :, :3], None), ("diffuse", "RGB", aov, None)],
    )
    result = run_cli(["convert", tmp_path / "multi.exr", tmp_path / "out.exr", "--to", "sphere",
                      "--size", "16", "--alpha"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    written = openexr_parts(tmp_path / "out.exr")
    assert sorted(written["beauty"]) == ["A", "B", "G", "R"] and sorted(written["diffuse"]) == [
        "B",
        "G",
        "R",
    ]
    assert written["beauty"]["A"].max() == 1.0 and written["beauty"]["A"].min() == 0.0


def test_formats_of_one_image_ask_for_a_part_and_mips_for_level_files(tmp_path, beauty_and_aov):
    rgba, aov = beauty_and_aov
    write_parts(
        tmp_path / "multi.exr", [("beauty", "RGBA", rgba, None), ("diffuse", "RGB", aov, None)]
    )
    for output, extra in (("out.png", []), ("out.exr", ["--mips"])):
        result = run_cli(
            ["convert", tmp_path / "multi.exr", tmp_path / output, "--to", "latlong", *extra]
        )
        assert result.exit_code == 1
        (line,) = stderr_lines(result)
        assert "--part" in line, line
        assert not os.path.exists(tmp_path / output)
    result = run_cli(["convert", tmp_path / "multi.exr", tmp_path / "m_{level}.exr", "--to", "latlong",
                      "--size", "8", "--mips", "2"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert list(openexr_parts(tmp_path / "m_1.exr")) == ["beauty", "diffuse"]
