"""Graph files (envconv.engine.graph) and ``envconv run``: variables, validation, --dry-run.

Truth: outputs equal ``envconv.convert`` of the same input; plans are checked against the
layouts' size rules of docs/geometry.md (W × H from N and G) and against the files a real run writes.
"""

from __future__ import annotations

import json
import textwrap

import numpy as np
import pytest
from conftest import run_cli

import envconv
from envconv import io
from envconv.engine.graph import load_graph
from envconv.errors import UsageError


@pytest.fixture(scope="module")
def hdri(tmp_path_factory):
    """Two small lat-longs in a folder: a 64×32 and a 32×16."""
    import analytic
    import naive

    folder = tmp_path_factory.mktemp("hdri")
    for name, n in (("alpha", 16), ("beta", 8)):
        pixels = naive.pixel_average("latlong", n, analytic.smooth_radiance, samples=2)
        io.write(envconv.EnvMap(pixels.astype(np.float32), "latlong"), folder / f"{name}.exr")
    return folder


def _graph(tmp_path, text, name="graph.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


GRAPH = """\
    inputs = ["{hdri}/*.exr"]
    [vars]
    out = "build"

    [[steps]]
    step = "read"
    from = "latlong"

    [[steps]]
    step = "resample"
    to = "cube-vcross"
    size = 8

    [[steps]]
    step = "write"
    path = "{{out}}/{{stem}}_{{layout}}.exr"

    [[steps]]
    step = "resample"
    to = "paraboloid"
    alpha = true
    guard = 1

    [[steps]]
    step = "write"
    path = "{{out}}/{{stem}}_{{layout}}_{{size}}.exr"
    """


def test_graph_with_variables_runs_once_per_input(hdri, tmp_path):
    path = _graph(tmp_path, GRAPH.format(hdri=hdri))
    result = run_cli(["run", path])
    assert result.exit_code == 0, result.output
    for stem in ("alpha", "beta"):
        source = io.read(hdri / f"{stem}.exr")
        cross = io.read(tmp_path / "build" / f"{stem}_cube-vcross.exr")
        assert np.array_equal(cross.pixels, envconv.convert(source, "cube-vcross", size=8).pixels)
        para = envconv.convert(source, "paraboloid", alpha=True, guard=1)
        written = io.read(tmp_path / "build" / f"{stem}_paraboloid_{para.size}.exr")
        assert np.array_equal(written.pixels, para.pixels)


def test_dry_run_prints_the_plan_without_pixels(hdri, tmp_path, monkeypatch):
    path = _graph(tmp_path, GRAPH.format(hdri=hdri))

    def no_pixels(*args, **kwargs):
        raise AssertionError("dry run read pixels")

    monkeypatch.setattr(io.reader, "read_file", no_pixels)
    result = run_cli(["run", path, "--dry-run"])
    assert result.exit_code == 0, result.output
    assert not (tmp_path / "build").exists()
    text = result.stdout
    # alpha is N=16 → paraboloid default N keeps the horizon pitch; compute it independently.
    for stem, n in (("alpha", 16), ("beta", 8)):
        assert str(hdri / f"{stem}.exr") in text
        assert "cube-vcross  N=8  G=0  24x32  1 level" in text
        fake = envconv.EnvMap(np.zeros((n, 2 * n, 3), np.float32), "latlong")
        m = envconv.resample.convert.default_size(fake, "paraboloid")
        assert f"paraboloid  N={m}  G=1  {2 * (m + 2)}x{m + 2}  1 level" in text
        assert str(tmp_path / "build" / f"{stem}_paraboloid_{m}.exr") in text


def test_json_graph_and_explicit_reads(hdri, tmp_path):
    graph = {"steps": [
        {"step": "read", "path": str(hdri / "beta.exr")},
        {"step": "rotate", "yaw": 90},
        {"step": "resample", "to": "cube-faces", "size": 4},
        {"step": "write", "path": "faces/{stem}_{face}.exr"},
    ]}  # fmt: skip
    path = tmp_path / "g.json"
    path.write_text(json.dumps(graph))
    result = run_cli(["run", path])
    assert result.exit_code == 0, result.output
    written = io.read(tmp_path / "faces" / "beta_{face}.exr")
    direct = envconv.convert(io.read(hdri / "beta.exr"), "cube-faces", size=4, rotate=(90, 0, 0))
    assert np.array_equal(written.pixels, direct.pixels)


@pytest.mark.parametrize(
    "steps, needle",
    [
        ('[[steps]]\nstep = "resample"\nto = "sphere"\nsize = 0\n', "step 2 (resample): key 'size'"),
        ('[[steps]]\nstep = "resample"\nto = "spehre"\n', "step 2 (resample): key 'to'"),
        ('[[steps]]\nstep = "resample"\nto = "sphere"\nsamplez = 2\n', "step 2 (resample): unknown key 'samplez'"),
        ('[[steps]]\nstep = "resample"\nto = "sphere"\nguard = "wide"\n', "step 2 (resample): key 'guard'"),
        ('[[steps]]\nstep = "blur"\n', "step 2: key 'step'"),
        ('[[steps]]\nstep = "write"\npath = "{nope}.exr"\n', "step 2 (write): path: unknown variable {nope}"),
        ('[[steps]]\nstep = "write"\n', "step 2 (write): missing key 'path'"),
        ('[[steps]]\nstep = "exposure"\nstops = "bright"\n', "step 2 (exposure): key 'stops'"),
    ],
)  # fmt: skip
def test_validation_errors_name_file_step_and_key(hdri, tmp_path, steps, needle):
    text = f'[[steps]]\nstep = "read"\npath = "{hdri}/alpha.exr"\n\n{steps}'
    if "write" not in steps:
        text += '\n[[steps]]\nstep = "write"\npath = "out.exr"\n'
    path = _graph(tmp_path, text)
    with pytest.raises(UsageError) as info:
        load_graph(path)
    assert str(path) in str(info.value) and needle in str(info.value)
    result = run_cli(["run", path])
    assert result.exit_code == 2  # a graph that does not validate is bad usage
    assert needle in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out.exr").exists()


def test_bad_files_and_inputs(tmp_path):
    bad = _graph(tmp_path, "steps = [[[", "bad.toml")
    assert "not valid TOML" in run_cli(["run", bad]).stderr
    nothing = _graph(
        tmp_path, 'inputs = ["none/*.exr"]\n[[steps]]\nstep = "write"\npath = "o.exr"\n'
    )
    result = run_cli(["run", nothing])
    assert result.exit_code == 1 and "no input files match" in result.stderr
    extra = _graph(tmp_path, 'colour = 1\n[[steps]]\nstep = "write"\npath = "o.exr"\n', "x.toml")
    assert "unknown top-level key 'colour'" in run_cli(["run", extra]).stderr


# --- issue 15: every key type-checked before any work; one home for samples/guard/mips -------


def test_every_key_of_every_step_has_a_check():
    from envconv.engine.graph import CHECKS, STEP_KEYS

    missing = {(kind, key) for kind, keys in STEP_KEYS.items() for key in keys if key not in CHECKS}
    assert not missing, missing


@pytest.mark.parametrize(
    ("step", "entry"),
    [("write", "bit_depth = 16"), ("write", 'compression = ["zip"]'), ("write", "no_clobber = 1"),
     ("write", 'preview = 3'), ("resample", "in_convention = 5"), ("resample", "guard = 1.5"),
     ("resample", "samples = 0"), ("resample", 'mips = "ggx:0"'), ("resample", 'up = "x"'),
     ("resample", "rotate = [1, 2]"), ("read", "exposure = true"), ("read", "part = -1"),
     ("read", 'faces = "nope"'), ("colorspace", "to = 3")],
)  # fmt: skip
def test_wrong_types_and_choices_name_the_step_and_the_key(tmp_path, step, entry):
    key = entry.split(" =")[0]
    tables = {
        "read": '[[steps]]\nstep = "read"\npath = "in.exr"\n',
        "colorspace": '[[steps]]\nstep = "colorspace"\nto = "ACEScg"\n',
        "resample": '[[steps]]\nstep = "resample"\nto = "latlong"\n',
        "write": '[[steps]]\nstep = "write"\npath = "o.exr"\n',
    }
    text = "".join(tables[k] + (entry + "\n" if k == step else "")
                   for k in ("read", "colorspace", "resample", "write"))  # fmt: skip
    text = text.replace('to = "ACEScg"\nto = 3', "to = 3")
    with pytest.raises(UsageError, match=rf"step \d \({step}\): key '{key}': expected "):
        load_graph(_graph(tmp_path, text))


def test_samples_guard_and_mips_follow_one_rule_in_library_cli_and_graph(tmp_path):
    """resample.options.check_* is the one home: each bad value is refused by all three front doors."""
    from envconv.resample.options import check_guard, check_mips, check_samples

    assert check_mips("ggx:3") == (3, True) and check_mips("box") == (True, False)
    assert check_mips(0) == (True, False) and check_mips(None) == (None, False)
    source = tmp_path / "in.exr"
    io.write(envconv.EnvMap(np.ones((8, 16, 3), np.float32), "latlong"), source)
    for option, bad, check in [("samples", 65, check_samples), ("guard", -1, check_guard),
                               ("mips", "ggx:0", check_mips)]:  # fmt: skip
        with pytest.raises(UsageError):
            check(bad)
        result = run_cli(["convert", source, tmp_path / "o.exr", "--to", "latlong",
                          f"--{option}", bad])  # fmt: skip
        assert result.exit_code == 2, (option, result.output)
        text = f'[[steps]]\nstep = "read"\npath = "in.exr"\n[[steps]]\nstep = "resample"\n' \
               f'to = "latlong"\n{option} = {json.dumps(bad)}\n[[steps]]\nstep = "write"\n' \
               f'path = "o.exr"\n'  # fmt: skip
        with pytest.raises(UsageError, match=f"key '{option}'"):
            load_graph(_graph(tmp_path, text))
    assert not (tmp_path / "o.exr").exists()
