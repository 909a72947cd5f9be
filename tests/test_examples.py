"""The examples of docs/ run as documented (examples/*.sh, *.py, graph.toml), on a copy.

Truth: the outputs are compared with direct ``envconv.convert`` calls and the reports with the
input folder.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import envconv
from envconv import io

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
STEMS = sorted(p.stem for p in (EXAMPLES / "data").glob("*-latlong-512.exr"))


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A copy of examples/ (scripts, graph and data), so nothing is written into the repo."""
    root = tmp_path_factory.mktemp("examples") / "examples"
    shutil.copytree(EXAMPLES, root, ignore=shutil.ignore_patterns("build", "*.png"))
    return root


def _run(args, cwd):
    env = {**os.environ, "PATH": os.path.dirname(sys.executable) + os.pathsep + os.environ["PATH"]}
    done = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)
    return done


def test_shell_example(workdir):
    done = _run(["bash", "shell.sh", "out"], workdir)
    assert done.returncode == 0, done.stderr
    out = workdir / "out"
    chained, converted = io.read(out / "park_cross.exr"), io.read(out / "park_cross_convert.exr")
    assert np.array_equal(chained.pixels, converted.pixels)
    para = io.read(out / "park_para.exr")
    assert (para.layout.name, para.size, para.guard, para.channels[-1]) == (
        "paraboloid",
        64,
        2,
        "A",
    )


def test_graph_example(workdir):
    plan = _run(["envconv", "run", "graph.toml", "--dry-run"], workdir)
    assert plan.returncode == 0, plan.stderr
    assert not (workdir / "build").exists()
    assert plan.stdout.count("cube-vcross  N=64  G=0  192x256  1 level") == len(STEMS)
    done = _run(["envconv", "run", "graph.toml"], workdir)
    assert done.returncode == 0, done.stderr
    for stem in STEMS:
        source = io.read(workdir / "data" / f"{stem}.exr")
        expected = envconv.convert(source, "cube-vcross", size=64, rotate="90")
        written = io.read(workdir / "build" / "graph" / f"{stem}_cube-vcross.exr")
        assert np.array_equal(written.pixels, expected.pixels.astype(np.float16).astype(np.float32))
        assert (workdir / "build" / "graph" / f"{stem}_paraboloid_62.exr").exists()
        assert str(workdir / "build" / "graph" / f"{stem}_paraboloid_62.exr") in plan.stdout


def test_batch_example(workdir):
    done = _run(["bash", "batch.sh", "out-batch"], workdir)
    assert done.returncode == 0, done.stderr
    report = json.loads((workdir / "out-batch" / "report.json").read_text())
    assert report["summary"]["done"] == len(STEMS) == len(report["files"])
    assert [Path(r["input"]).stem for r in report["files"]] == STEMS
    assert f"{len(STEMS)} files: 0 done, {len(STEMS)} skipped, 0 failed" in done.stdout
    for record in report["files"]:
        cross = io.read(record["outputs"][0])
        direct = envconv.convert(io.read(record["input"]), "cube-vcross", size=64)
        assert np.array_equal(cross.pixels, direct.pixels.astype(np.float16).astype(np.float32))


def test_python_example(workdir):
    done = _run([sys.executable, "pipeline_api.py", "out-py"], workdir)
    assert done.returncode == 0, done.stderr
    assert "batch: {'done': 4, 'skipped': 0, 'failed': 0}" in done.stdout
    assert len(list((workdir / "out-py" / "recipe").glob("*.exr"))) == len(STEMS)


def test_cluster_example(workdir):
    pytest.importorskip("dask.distributed")
    done = _run([sys.executable, "cluster.py", "out-dask"], workdir)
    assert done.returncode == 0, done.stderr
    report = json.loads((workdir / "out-dask" / "report.json").read_text())
    assert [r["status"] for r in report["files"]] == ["done"] * len(STEMS)


def test_every_layout_example(workdir):
    """run-example.sh's job: every layout written, energy kept, round trip back to lat-long.

    Truth: the report's mean radiance of each layout against the input's (solid-angle
    integrals), and the round trip against the input itself.
    """
    done = _run(
        [sys.executable, "every_layout.py", "data/venice-latlong-512.exr", "every"], workdir
    )
    assert done.returncode == 0, done.stderr
    rows = {line.split()[0]: line for line in done.stdout.splitlines()[2:] if "dB" in line}
    assert set(rows) == set(envconv.layouts.LAYOUTS)
    source = envconv.read(workdir / "data" / "venice-latlong-512.exr")
    for name, line in rows.items():
        mean = json.loads(line[line.index("[") : line.index("]") + 1])
        psnr = line.split("dB")[0].split()[-1]
        floor = 40.0
        if envconv.layouts.get_layout(name).partial:  # a view: the input's mean where it sees
            seen = _seen_mean(source, workdir / "every" / f"venice-{name}.exr")
            assert np.allclose(mean, seen, rtol=0.005), (name, mean, seen)
            # ... and its round trip over the part it sees, Venice's most detailed (a cube's
            # round trip measures 38.7 dB there, the perspective view's 39.3 dB).
            floor = 36.0
        elif name != "tennisball":  # tennisball's faces overlap, so its image mean differs
            assert np.allclose(mean, _sphere_mean(source), rtol=0.005), (name, mean)
        assert psnr == "inf" or float(psnr) > floor, (name, psnr)
    assert len(list((workdir / "every").glob("*.exr"))) == len(envconv.layouts.LAYOUTS) + 6


def _seen_mean(source, view_path):
    """The source's mean radiance over what the view in ``view_path`` sees (its coverage)."""
    from envconv.layouts.geometry import pixel_solid_angles

    seen = envconv.convert(envconv.read(view_path), "latlong", size=source.size, alpha=True)
    omega = pixel_solid_angles(source.layout, source.size) * seen.pixels[..., 3]
    return (source.pixels[..., :3] * omega[..., None]).sum(axis=(0, 1)) / omega.sum()


def _sphere_mean(envmap):
    from envconv.layouts.geometry import pixel_solid_angles

    omega = pixel_solid_angles(envmap.layout, envmap.size, envmap.guard)
    return (envmap.pixels[..., :3] * omega[..., None]).sum(axis=(0, 1)) / omega.sum()


def _doc_batch_script() -> str:
    """The Python block of docs/python.md that starts a batch."""
    import re

    text = (EXAMPLES.parent / "docs" / "python.md").read_text("utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    (block,) = [b for b in blocks if "run_batch(" in b]
    return block


def test_the_batch_snippet_of_the_docs_is_the_example_and_runs_as_a_saved_script(workdir):
    """docs/python.md shows examples/batch_api.py as it is (after its docstring), and the
    script runs on two worker processes: every input converted, as a direct convert does."""
    script = (workdir / "batch_api.py").read_text("utf-8")
    assert _doc_batch_script().strip() in script
    done = _run([sys.executable, "batch_api.py", "out-batch-api"], workdir)
    assert done.returncode == 0, done.stderr
    assert "{'done': 4, 'skipped': 0, 'failed': 0}" in done.stdout
    report = json.loads((workdir / "out-batch-api" / "report.json").read_text())
    for record in report["files"]:
        (path,) = record["outputs"]
        direct = envconv.convert(io.read(record["input"]), "cube-vcross", size=64)
        written = io.read(path).pixels
        assert np.array_equal(written, direct.pixels.astype(np.float16).astype(np.float32))


@pytest.mark.parametrize("breakage, message", [
    ("unguarded", 'under `if __name__ == "__main__":`'),
    ("import", "ImportError: this environment cannot import what the worker needs"),
])  # fmt: skip
def test_a_worker_that_dies_on_import_stops_the_batch_with_one_line(workdir, breakage, message):
    """The example without its guard (every worker would start the batch again) and with an
    import that fails in the workers only: the batch stops at once with WorkerStartError, one
    line saying why; the workers' tracebacks do not reach the terminal and nothing hangs."""
    script = (workdir / "batch_api.py").read_text("utf-8")
    if breakage == "unguarded":
        script = script.replace('if __name__ == "__main__":\n    main(', "if True:\n    main(")
    else:
        script = script.replace(
            "import sys\n", 'import sys\n\nif __name__ == "__mp_main__":\n    raise ImportError('
            '"this environment cannot import what the worker needs")\n', 1)  # fmt: skip
    (workdir / f"broken_{breakage}.py").write_text(script, "utf-8")
    done = _run([sys.executable, f"broken_{breakage}.py", f"out-{breakage}"], workdir)
    assert done.returncode == 1
    # The script's own traceback ends with the one line; the workers printed nothing here.
    assert done.stderr.count("Traceback") == 1, done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("envconv.engine.workers.WorkerStartError: batch workers cannot start")
    assert message in last, last
    assert "bootstrapping phase" not in done.stderr
    assert not (workdir / f"out-{breakage}").exists()
