"""``envconv batch --dask``: the same jobs on a LocalCluster of two worker processes with two
threads each (two jobs at once in one process: their thread counts and output must not mix),
the same report.

Truth: the local run's report and progress lines (timings removed), and ``envconv.convert``.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from conftest import run_cli

import envconv
from envconv import io

distributed = pytest.importorskip("dask.distributed")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    import analytic
    import naive

    folder = tmp_path_factory.mktemp("in")
    for i in range(6):
        pixels = (1 + i) * naive.pixel_average("latlong", 8, analytic.smooth_radiance, 2)
        io.write(envconv.EnvMap(pixels.astype(np.float32), "latlong"), folder / f"s{i}.exr")
    (folder / "broken.exr").write_bytes(b"\x76\x2f\x31\x01 truncated")
    return folder


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=2, processes=True, dashboard_address=None
    ) as local:
        yield local


def _run(inputs, out, report, *extra):
    return run_cli(["batch", str(inputs), "--out", str(out / "{stem}_{layout}.exr"),
                    "--report", str(report), *extra,
                    "resample", "--to", "cube-hcross", "--size", 4,
                    "resample", "--to", "angular", "--size", 8])  # fmt: skip


def _normalise(report_path, out):
    report = json.loads(report_path.read_text())
    report["summary"].pop("seconds")
    for record in report["files"]:
        record.pop("seconds")
        record.pop("timings")  # wall-clock seconds too
        for entry in record["maps"]:
            entry.pop("seconds")
    return json.loads(json.dumps(report).replace(str(out), "OUT"))


def _progress(result, out):
    lines = [re.sub(r" \(\d+\.\d+ s\)", "", line) for line in result.stderr.splitlines()]
    lines = [re.sub(r"\[\s*\d+/\d+\]", "[n/7]", line).replace(str(out), "OUT") for line in lines]
    return sorted(lines)


def test_dask_run_equals_local_run(inputs, cluster, tmp_path):
    local_out, dask_out = tmp_path / "local", tmp_path / "dask"
    local = _run(inputs, local_out, tmp_path / "local.json")
    remote = _run(inputs, dask_out, tmp_path / "dask.json", "--dask", cluster.scheduler_address)
    assert local.exit_code == remote.exit_code == 1  # broken.exr failed in both
    assert _normalise(tmp_path / "local.json", local_out) == _normalise(
        tmp_path / "dask.json", dask_out
    )
    assert _progress(local, local_out) == _progress(remote, dask_out)
    assert re.sub(r" in .*", "", local.stdout) == re.sub(r" in .*", "", remote.stdout)
    for i in range(6):
        source = io.read(inputs / f"s{i}.exr")
        for layout, size in (("cube-hcross", 4), ("angular", 8)):
            written = io.read(dask_out / f"s{i}_{layout}.exr")
            assert np.array_equal(written.pixels, envconv.convert(source, layout, size=size).pixels)


def test_unreachable_scheduler_is_one_line(inputs, tmp_path):
    import dask

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        result = _run(inputs, tmp_path, tmp_path / "r.json", "--dask", "tcp://127.0.0.1:1")
    assert result.exit_code == 1
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "cannot reach the Dask scheduler" in lines[0]
