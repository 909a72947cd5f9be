"""How errors read and which status they exit with (envconv.cli.main, envconv.cli.messages),
and the layout names the registry accepts (envconv.layouts)."""

from __future__ import annotations

import pytest
from conftest import run_cli, stderr_lines

import envconv.views.info
from envconv.cli.messages import did_you_mean, one_line, step_typo
from envconv.errors import ImageIOError, LayoutError, UsageError
from envconv.layouts import ALIASES, FAMILIES, LAYOUTS, get_layout, resolve_layout_name


@pytest.mark.parametrize("exc, status, line", [
    (UsageError("two options that contradict"), 2, "envconv: error: two options that contradict"),
    (ImageIOError("cannot read x.exr:\n  bad\n\n  chunk"), 1, "envconv: error: cannot read x.exr: bad chunk"),
    (MemoryError("Unable to allocate 4 GiB"), 1, "envconv: error: out of memory: Unable to allocate 4 GiB"),
    (RuntimeError("boom"), 3, "envconv: internal error: RuntimeError: boom"),
])  # fmt: skip
def test_each_kind_of_error_has_its_status_and_one_line(monkeypatch, exc, status, line):
    """2 usage, 1 run-time failure (out of memory too), 3 a bug; never a traceback."""

    def fail(*args, **kwargs):
        raise exc

    monkeypatch.delenv("ENVCONV_DEBUG", raising=False)
    monkeypatch.setattr(envconv.views.info, "describe", fail)
    result = run_cli(["info", "any.exr"])
    assert result.exit_code == status
    assert stderr_lines(result) == [line] and result.stdout == ""


def test_one_line_joins_lines():
    assert one_line("Missing option '--to'. Choose from:\n\tlatlong,\n\tsphere") == (
        "Missing option '--to'. Choose from: latlong, sphere"
    )
    assert one_line("\n \n") == "unknown error"


def test_did_you_mean_and_step_typos():
    names = ["read", "resample", "rotate", "write"]
    assert did_you_mean("resampel", names) == "; did you mean 'resample'?"
    assert did_you_mean("zzz", names) == ""
    assert step_typo(["sky.exr", "resampel", "--to", "latlong"], names) == "resampel"
    # file names (a dot or a slash), options and real steps are never taken for typos
    assert step_typo(["write.exr", "out/rotate", "--rotat", "write"], names) is None


def test_layout_names_aliases_and_families():
    for name in LAYOUTS:
        assert resolve_layout_name(name.upper()) == name and get_layout(name).name == name
    assert ALIASES == {"equirect": "latlong", "equirectangular": "latlong"}
    assert get_layout("Equirectangular") is LAYOUTS["latlong"]
    assert set(FAMILIES["cubemap"]) == {n for n in LAYOUTS if n.startswith("cube-")}
    with pytest.raises(
        LayoutError, match="'cubemap' names several layouts; choose one of cube-vcross"
    ):
        get_layout("cubemap")
    with pytest.raises(LayoutError, match="did you mean 'paraboloid'"):
        get_layout("parabloid")
    with pytest.raises(LayoutError, match=r"unknown layout 'qqq' \(known: latlong"):
        get_layout("qqq")


def test_a_python_warning_is_one_line():
    import io

    from envconv.cli.messages import show_warning

    stream = io.StringIO()
    show_warning("invalid value\n  encountered", RuntimeWarning, "/x/quantize.py", 136, stream)
    assert stream.getvalue() == (
        "envconv: warning: RuntimeWarning: invalid value encountered (quantize.py:136)\n"
    )


def test_layouts_lists_the_aliases():
    lines = run_cli(["layouts"]).stdout.splitlines()
    (latlong,) = [line for line in lines if line.startswith("latlong ")]
    assert latlong.endswith("(also equirect, equirectangular)")
