"""``envconv batch``: 20 small files, 2 corrupt; -j 2; --skip-existing; --update; the report.

Truth: each output equals ``envconv.convert`` of its input (bit for bit) and, for the analytic
inputs, the analytic environment within tolerance; the report is checked against the files.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from conftest import run_cli

import envconv
from envconv import io
from envconv.engine.batch import expand_inputs, worker_threads

N_GOOD = 18


def _analytic(index: int):
    import analytic
    import naive

    scale = 1.0 + index / 8  # every file differs
    return naive.pixel_average("latlong", 16, lambda d: scale * analytic.smooth_radiance(d), 2)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """18 float 32×16 lat-longs, a garbage file and a truncated EXR, in one folder."""
    folder = tmp_path_factory.mktemp("in")
    for i in range(N_GOOD):
        env = envconv.EnvMap(_analytic(i).astype(np.float32), "latlong")
        io.write(env, folder / f"sky{i:02d}.exr")
    (folder / "garbage.exr").write_bytes(b"this is not an image")
    whole = (folder / "sky00.exr").read_bytes()
    (folder / "truncated.exr").write_bytes(whole[: len(whole) // 2])
    return folder


def _batch(inputs, out, *extra):
    template = str(out / "{stem}_{layout}.exr")
    return run_cli(["batch", str(inputs), "--out", template, *extra,
                    "resample", "--to", "cube-vcross", "--size", 8,
                    "resample", "--to", "sphere", "--size", 8])  # fmt: skip


def _strip_times(report):
    report["summary"].pop("seconds")
    for record in report["files"]:
        record.pop("seconds")
        record.pop("timings")  # wall-clock seconds too
        for entry in record["maps"]:
            entry.pop("seconds")
    return report


def test_batch_with_corrupt_files(inputs, tmp_path):
    out, report_path = tmp_path / "out", tmp_path / "report.json"
    result = _batch(inputs, out, "--report", report_path)
    assert result.exit_code == 1
    assert f"20 files: {N_GOOD} done, 0 skipped, 2 failed" in result.stdout
    report = json.loads(report_path.read_text())
    assert report["summary"]["done"] == N_GOOD and report["summary"]["failed"] == 2
    records = {os.path.basename(r["input"]): r for r in report["files"]}
    assert len(report["files"]) == 20 and set(records) == {
        *(f"sky{i:02d}.exr" for i in range(N_GOOD)),
        "garbage.exr",
        "truncated.exr",
    }
    for bad in ("garbage.exr", "truncated.exr"):
        assert records[bad]["status"] == "failed" and records[bad]["outputs"] == []
        assert bad in records[bad]["error"]
        assert any(bad in line and "failed" in line for line in result.stderr.splitlines())
    for i in range(N_GOOD):
        record = records[f"sky{i:02d}.exr"]
        expected = [str(out / f"sky{i:02d}_cube-vcross.exr"), str(out / f"sky{i:02d}_sphere.exr")]
        assert record["status"] == "done" and record["error"] is None
        assert record["outputs"] == expected and record["seconds"] >= 0
        source = io.read(inputs / f"sky{i:02d}.exr")
        cross = io.read(expected[0])
        assert np.array_equal(cross.pixels, envconv.convert(source, "cube-vcross", size=8).pixels)
        sphere = io.read(expected[1], layout="sphere")
        assert np.array_equal(sphere.pixels, envconv.convert(source, "sphere", size=8).pixels)
    # The analytic truth: a constant scale per file shows in the outputs' ratio.
    a, b = (io.read(out / f"sky{i:02d}_cube-vcross.exr").pixels for i in (0, 8))
    assert np.allclose(b, a * 2.0, rtol=1e-5)


def test_parallel_jobs_match_one_job(inputs, tmp_path):
    one, two = tmp_path / "one", tmp_path / "two"
    r1 = _batch(inputs, one, "--report", tmp_path / "r1.json")
    r2 = _batch(inputs, two, "-j", 2, "--report", tmp_path / "r2.json")
    assert r1.exit_code == r2.exit_code == 1
    first = _strip_times(json.loads((tmp_path / "r1.json").read_text()))
    second = _strip_times(json.loads((tmp_path / "r2.json").read_text()))
    assert json.dumps(first).replace(str(one), "X") == json.dumps(second).replace(str(two), "X")
    for name in sorted(os.listdir(one)):
        assert np.array_equal(io.read(one / name, layout=None).pixels, io.read(two / name).pixels)
    assert len(os.listdir(two)) == 2 * N_GOOD


def test_skip_existing_and_update(inputs, tmp_path):
    out = tmp_path / "out"
    assert _batch(inputs, out).exit_code == 1
    stamps = {name: os.stat(out / name).st_mtime_ns for name in os.listdir(out)}

    skipped = _batch(inputs, out, "--skip-existing", "--report", tmp_path / "s.json")
    assert f"{N_GOOD} skipped, 2 failed" in skipped.stdout
    assert {n: os.stat(out / n).st_mtime_ns for n in os.listdir(out)} == stamps
    report = json.loads((tmp_path / "s.json").read_text())
    done = [r for r in report["files"] if r["status"] == "skipped"]
    assert all(len(r["outputs"]) == 2 for r in done)

    # Update mode: redo only an input that is newer than its outputs, or lacks one.
    newer = inputs / "sky03.exr"
    future = max(stamps.values()) / 1e9 + 100
    os.utime(newer, (future, future))
    (out / "sky05_sphere.exr").unlink()
    try:
        updated = _batch(inputs, out, "--update", "--report", tmp_path / "u.json")
    finally:
        os.utime(newer, None)
    assert f"2 done, {N_GOOD - 2} skipped, 2 failed" in updated.stdout
    redone = {os.path.basename(r["input"]) for r in
              json.loads((tmp_path / "u.json").read_text())["files"] if r["status"] == "done"}  # fmt: skip
    assert redone == {"sky03.exr", "sky05.exr"}
    assert os.stat(out / "sky03_cube-vcross.exr").st_mtime_ns > stamps["sky03_cube-vcross.exr"]
    assert os.stat(out / "sky04_cube-vcross.exr").st_mtime_ns == stamps["sky04_cube-vcross.exr"]
    assert (out / "sky05_sphere.exr").exists()


def test_usage_errors_before_any_work(inputs, tmp_path):
    out = tmp_path / "o"
    cases = [
        (["batch", str(inputs / "*.exr"), "--out", str(out / "same.exr"),
          "resample", "--to", "sphere"], "would both write"),
        (["batch", str(inputs / "*.exr"), "resample", "--to", "sphere"], "give --out or a write"),
        (["batch", str(tmp_path / "none" / "*.exr"), "--out", "x.exr"], "no input files match"),
        (["batch", str(inputs), "--out", str(out / "{stem}.exr"), "--skip-existing", "--update"],
         "exclude each other"),
        (["batch", str(inputs), "--out", str(out / "{stem}.exr"), "write", "y.exr"],
         "either --out or write steps"),
        (["read", str(inputs / "sky00.exr"), "batch", str(inputs)], "batch must come first"),
    ]  # fmt: skip
    for args, needle in cases:
        result = run_cli(args)
        assert result.exit_code != 0 and needle in result.stderr, (args, result.output)
    assert not out.exists()


def test_batch_recipe_with_read_options_and_write_step(inputs, tmp_path):
    result = run_cli(["batch", str(inputs / "sky0[12].exr"), "read", "--from", "latlong",
                      "exposure", "1", "resample", "--to", "cube-hstrip", "--size", 4,
                      "write", str(tmp_path / "{stem}.{ext}")])  # fmt: skip
    assert result.exit_code == 0, result.output
    for i in (1, 2):
        source = io.read(inputs / f"sky{i:02d}.exr")
        expected = envconv.convert(source, "cube-hstrip", size=4).pixels * 2
        assert np.allclose(io.read(tmp_path / f"sky{i:02d}.exr").pixels, expected, rtol=1e-6)


def test_expand_inputs_and_threads(inputs):
    files = expand_inputs([str(inputs / "sky0*.exr"), str(inputs / "sky01.exr")])
    assert files == sorted(set(files)) and len(files) == 10  # sky00..sky09, no duplicate
    assert len(expand_inputs([str(inputs)])) == 20
    assert worker_threads(2, cores=2) == 1 and worker_threads(1, cores=8) == 8
    assert worker_threads(3, cores=8) == 2 and worker_threads(16, cores=2) == 1


def test_missing_dask_is_one_line(inputs, tmp_path, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "dask.distributed", None)  # import now fails
    result = _batch(inputs, tmp_path, "--dask", "tcp://127.0.0.1:8786")
    assert result.exit_code == 2  # an option this install cannot honour: usage, not a bad file
    assert result.stderr.strip() == (
        "envconv: error: --dask needs dask.distributed; install it with pip install 'envconv[dask]'"
    )


def test_progress_bar_on_a_terminal(capsys):
    from envconv.cli.progress import Progress

    progress = Progress(4, tty=True)
    for status in ("done", "skipped", "failed", "done"):
        record = {"input": f"{status}.exr", "status": status, "seconds": 0.1, "error": "bad"}
        progress.update(record)
    progress.close()
    err = capsys.readouterr().err
    assert err.count("\r[") == 4 and "ETA" in err
    assert "[########################] 4/4  done 2  skipped 1  failed 1" in err
    assert "failed  failed.exr (0.10 s): bad\n" in err  # failures get a line of their own


# --- issue 15: the output policy across the jobs of a batch, before any job runs -------------


def test_make_jobs_applies_the_output_policy_across_jobs(tmp_path):
    from envconv.engine.batch import make_jobs
    from envconv.engine.pipeline import Pipeline, Resample, Write
    from envconv.errors import UsageError

    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    for path in (a, b):
        io.write(envconv.EnvMap(np.ones((4, 8, 3), np.float32), "latlong"), path)
    os.symlink(b, tmp_path / "link.exr")

    def jobs(*steps, no_clobber=False):
        return make_jobs([str(a), str(b)], Pipeline(list(steps)), no_clobber)

    # a's output is b through a link: any input of the batch is protected, not only the job's.
    with pytest.raises(UsageError, match="never writes onto its inputs"):
        jobs(Resample("latlong", size=4), Write(str(tmp_path / "{stem}_x.exr")),
             Write(str(tmp_path / "link.exr")))  # fmt: skip
    # {face} outputs are expanded: two jobs, one set of six files.
    with pytest.raises(UsageError, match="would both write .*same_px.exr"):
        jobs(Resample("cube-faces", size=4), Write(str(tmp_path / "same_{face}.exr")))
    # One job, two outputs on one path.
    with pytest.raises(UsageError, match="written twice"):
        jobs(Resample("latlong", size=4), Write(str(tmp_path / "{stem}.out.exr")),
             Resample("sphere", size=4), Write(str(tmp_path / "{stem}.out.exr")))  # fmt: skip
    (tmp_path / "b_y.exr").write_bytes(b"old")
    made = jobs(Resample("latlong", size=4), Write(str(tmp_path / "{stem}_y.exr")))
    with pytest.raises(UsageError, match="no-clobber"):
        jobs(Resample("latlong", size=4), Write(str(tmp_path / "{stem}_y.exr")), no_clobber=True)
    assert all(
        s.params["no_clobber"] is False for s in made[0].pipeline.steps if isinstance(s, Write)
    )
    assert (tmp_path / "b_y.exr").read_bytes() == b"old" and not (tmp_path / "a_y.exr").exists()
