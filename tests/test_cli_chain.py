"""The chained CLI: ``envconv read … resample … write … resample … write …``.

Truth: the same conversions made by ``envconv convert`` (bit for bit, pixels and metadata), and
the known-direction table of docs/geometry.md for a rotated direction-coded map.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import run_cli

import envconv
from envconv import io


@pytest.fixture(scope="module")
def sky(tmp_path_factory):
    import analytic
    import naive

    pixels = naive.pixel_average("latlong", 32, analytic.radiance, samples=2)
    path = tmp_path_factory.mktemp("src") / "sky.exr"
    io.write(envconv.EnvMap(pixels.astype(np.float32), "latlong"), path)
    return path


def _same_file(a, b) -> None:
    first, second = io.read(a), io.read(b)
    assert first.layout is second.layout and first.guard == second.guard
    assert first.channels == second.channels and first.pixel_type == second.pixel_type
    assert np.array_equal(first.pixels, second.pixels)
    drop = {"DateTime"}  # OpenImageIO stamps the time of writing
    assert {k: v for k, v in first.metadata.items() if k not in drop} == {
        k: v for k, v in second.metadata.items() if k not in drop
    }


def test_fan_out_equals_convert(sky, tmp_path):
    cross, para = tmp_path / "cross.exr", tmp_path / "para.exr"
    result = run_cli(["read", sky, "resample", "--to", "cube-vcross", "--size", 16, "write", cross,
                      "resample", "--to", "paraboloid", "--size", 16, "--alpha", "--guard", 2,
                      "write", para])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert result.stdout.split() == [str(cross), str(para)]
    for out, args in [
        (cross, ["--to", "cube-vcross", "--size", 16]),
        (para, ["--to", "paraboloid", "--size", 16, "--alpha", "--guard", 2]),
    ]:
        reference = tmp_path / f"ref_{out.name}"
        assert run_cli(["convert", sky, reference, *args]).exit_code == 0
        _same_file(out, reference)
    assert io.read(para).channels == ("R", "G", "B", "A")


def test_options_after_positional_and_variables(sky, tmp_path):
    out = tmp_path / "{stem}_{layout}_{size}.exr"
    result = run_cli(["read", sky, "--from", "latlong", "resample", "--to", "sphere",
                      "--size", 8, "write", out, "--help-not-an-option"])  # fmt: skip
    assert result.exit_code == 2  # an unknown option of write is a usage error
    result = run_cli(["read", sky, "--from", "latlong", "resample", "--to", "sphere",
                      "--size", 8, "write", out])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert io.read(tmp_path / "sky_sphere_8.exr", layout="sphere").size == 8


def test_negative_rotation_turns_the_environment(tmp_path):
    # A direction-coded lat-long: each pixel holds its own direction (docs/geometry.md formula).
    n = 32
    u = (np.arange(2 * n) + 0.5) / (2 * n)
    v = (np.arange(n) + 0.5) / n
    lon, lat = 2 * np.pi * (0.5 - u)[None, :], np.pi * (0.5 - v)[:, None]
    dirs = np.stack(np.broadcast_arrays(np.sin(lon) * np.cos(lat), np.sin(lat),
                                        np.cos(lon) * np.cos(lat)), axis=-1)  # fmt: skip
    src = tmp_path / "dirs.exr"
    io.write(envconv.EnvMap(dirs.astype(np.float32), "latlong"), src)
    out = tmp_path / "rot.exr"
    result = run_cli(["read", src, "rotate", "-90", "resample", "--to", "latlong", "write", out])
    assert result.exit_code == 0, result.output
    rotated = io.read(out).pixels
    # Yaw -90° carries what was at +X (u = 0.25) to +Z, the centre (u = 0.5, v = 0.5).
    centre = rotated[n // 2 - 1 : n // 2 + 1, n - 1 : n + 1].mean(axis=(0, 1))
    assert np.allclose(centre / np.linalg.norm(centre), [1, 0, 0], atol=0.02)
    # The --yaw form is the same step.
    again = tmp_path / "rot2.exr"
    assert run_cli(["read", src, "rotate", "--yaw", "-90", "resample", "--to", "latlong",
                    "write", again]).exit_code == 0  # fmt: skip
    assert np.array_equal(io.read(again).pixels, rotated)


def test_exposure_step_negative_stops(sky, tmp_path):
    out = tmp_path / "dim.exr"
    result = run_cli(["read", sky, "exposure", "-1", "write", out])
    assert result.exit_code == 0, result.output
    assert np.allclose(io.read(out).pixels, io.read(sky).pixels * 0.5, rtol=1e-6)


@pytest.mark.parametrize(
    "args, needle",
    [
        (["resample", "--to", "sphere", "write", "x.exr"], "step 1 (resample): comes before any read"),
        (["read", "{src}", "resample", "--to", "sphere"], "step 2 (resample): this resample is never written"),
        (["read", "{src}", "write", "{{oops}}.exr"], "unknown variable {oops}"),
        (["read", "{src}", "resample", "--to", "cube-faces", "write", "x.exr"], "put {face}"),
        (["read", "{src}", "resample", "--to", "sphere", "rotate", "9", "write", "x.exr"], "step 3 (rotate)"),
        (["read", "{src}", "info", "{src}"], "cannot be chained"),
        (["read", "missing.exr", "write", "x.exr"], "input file not found: missing.exr"),
    ],
)  # fmt: skip
def test_errors_are_one_line_and_nonzero(sky, tmp_path, args, needle):
    args = [a.replace("{src}", str(sky)) if a == "{src}" else a for a in args]
    args = [a.replace("{{oops}}", "{oops}") for a in args]
    result = run_cli(args)
    assert result.exit_code != 0
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert any(needle in line for line in lines), result.stderr
    assert "Traceback" not in result.output


def test_standalone_commands_still_work(sky, tmp_path):
    assert run_cli(["layouts"]).exit_code == 0
    info = run_cli(["info", sky, "--json"])
    assert info.exit_code == 0 and '"layout": "latlong"' in info.stdout
    out = tmp_path / "c.exr"
    result = run_cli(["convert", sky, out, "--to", "cube-hcross", "--size", 8])
    assert result.exit_code == 0 and io.read(out).layout.name == "cube-hcross"


def test_the_lazy_command_table_names_every_command_and_its_module():
    """``envconv.cli.main.COMMANDS`` lets the CLI import one command's module: it must list
    exactly the commands the modules define, each with the module that defines it."""
    import importlib
    import sys

    import envconv.cli  # noqa: F401

    main_module = sys.modules["envconv.cli.main"]
    for module in set(main_module.COMMANDS.values()):
        importlib.import_module(f"envconv.cli.{module}")
    registered = main_module.cli.commands
    assert set(registered) == set(main_module.COMMANDS)
    for name, command in registered.items():
        defined_in = command.callback.__module__.rsplit(".", 1)[-1]
        assert defined_in == main_module.COMMANDS[name], name
