"""``--json`` on convert, run and batch (docs/shell.md, "JSON output"): stdout is one JSON
document and nothing else, and every fact in it is checked against the files on disk, read
back by OpenImageIO and envconv's header probe; a dry run writes nothing and plans exactly
what the run then writes."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from conftest import write_plain
from hostile import assert_failed_cleanly, envconv

import envconv as ec


def _source(path, height=16, seed=1):
    pixels = np.random.default_rng(seed).uniform(0.1, 4, (height, 2 * height, 3))
    write_plain(path, pixels.astype(np.float32), {"compression": "zip"})
    return path


def _document(run, status=0) -> dict:
    assert run.returncode == status, run.stderr
    assert "Traceback" not in run.stderr
    return json.loads(run.stdout)  # the whole of stdout is one document


def _check_file(entry: dict, layout: str, size: int, guard: int, probe=None) -> None:
    """A written file against its JSON entry: bytes on disk, and what OpenImageIO reads;
    ``probe``: the path envconv's header probe places in the layout (a {face} template)."""
    import OpenImageIO as oiio

    path = entry["path"]
    assert entry["bytes"] == os.path.getsize(path)
    if entry.get("preview"):
        return
    spec = oiio.ImageInput.open(path).spec()
    assert tuple(spec.channelnames) == tuple(entry["channels"])
    assert str(spec.format) == entry["bit_depth"]
    found = ec.io.probe(probe or path)
    assert (found.layout.name, found.size, found.guard) == (layout, size, guard)
    assert len(found.levels) == entry["levels"]


def test_convert_json_describes_the_files_it_wrote(tmp_path):
    source = _source(tmp_path / "sky.exr")
    out = tmp_path / "sky_{face}.exr"
    run = envconv("convert", source, out, "--to", "cube-faces", "--size", "8", "--alpha",
                  "--preview", tmp_path / "look.png", "--json")  # fmt: skip
    doc = _document(run)
    assert (doc["command"], doc["dry_run"], doc["envconv"]) == ("convert", False, ec.__version__)
    assert doc["summary"] == {"done": 1, "skipped": 0, "failed": 0, "total": 1,
                              "seconds": doc["summary"]["seconds"]}  # fmt: skip
    (record,) = doc["files"]
    assert record["status"] == "done" and record["error"] is None
    names = ["px", "nx", "py", "ny", "pz", "nz"]
    expected = [str(tmp_path / f"sky_{n}.exr") for n in names] + [str(tmp_path / "look.png")]
    assert record["outputs"] == expected
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["sky.exr", "look.png", *(f"sky_{n}.exr" for n in names)]
    )
    timings = record["timings"]
    assert set(timings) == {"read", "resample", "write"} and min(timings.values()) > 0
    assert sum(timings.values()) <= record["seconds"] + 1e-3
    (entry,) = record["maps"]
    assert (entry["layout"], entry["size"], entry["guard"], entry["width"], entry["height"],
            entry["levels"], entry["channels"]) == ("cube-faces", 8, 0, 8, 8, 1,
                                                   ["R", "G", "B", "A"])  # fmt: skip
    assert [f["path"] for f in entry["files"]] == expected
    for file in entry["files"]:
        _check_file(file, "cube-faces", 8, 0, probe=out)
    assert entry["files"][-1]["preview"] is True


def test_convert_dry_run_json_writes_nothing_and_plans_what_the_run_writes(tmp_path):
    source = _source(tmp_path / "sky.exr", 32)
    args = ["--to", "cube-vcross", "--mips", "--guard", "1", "--alpha", "--json"]
    before = sorted(os.listdir(tmp_path))
    planned = _document(envconv("convert", source, tmp_path / "x.exr", *args, "--dry-run"))
    assert sorted(os.listdir(tmp_path)) == before
    assert planned["dry_run"] is True and planned["files"][0]["status"] == "planned"
    ran = _document(envconv("convert", source, tmp_path / "x.exr", *args))

    def facts(doc):
        maps = doc["files"][0]["maps"]
        return [{**m, "seconds": None,
                 "files": [{**f, "bytes": None} for f in m["files"]]} for m in maps]  # fmt: skip

    assert facts(planned) == facts(ran)
    (entry,) = ran["files"][0]["maps"]
    # No --size with --mips: N + 2G is a power of two, so every level holds whole cells.
    assert (entry["size"] + 2 * entry["guard"]) & (entry["size"] + 2 * entry["guard"] - 1) == 0
    _check_file(entry["files"][0], "cube-vcross", entry["size"], 1)
    assert (
        entry["levels"] == entry["files"][0]["levels"] == len(ec.io.mip_levels(tmp_path / "x.exr"))
    )


def test_a_failed_convert_prints_no_document(tmp_path):
    run = envconv("convert", tmp_path / "missing.exr", tmp_path / "o.exr", "--to", "latlong",
                  "--json")  # fmt: skip
    assert_failed_cleanly(run, 1, tmp_path, message="missing.exr")


def test_batch_json_has_a_record_per_input_and_exits_1_for_a_failure(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    _source(folder / "a.exr", 16, 1)
    _source(folder / "b.exr", 16, 2)
    (folder / "c.exr").write_bytes(b"not an image")
    out = tmp_path / "out" / "{stem}_{layout}.png"
    run = envconv("batch", folder, "--out", out, "--json", "resample", "--to", "sphere",
                  "--size", "8", "resample", "--to", "latlong", "--size", "4")  # fmt: skip
    doc = _document(run, status=1)
    assert doc["command"] == "batch"
    assert {k: doc["summary"][k] for k in ("done", "skipped", "failed", "total")} == {
        "done": 2, "skipped": 0, "failed": 1, "total": 3}  # fmt: skip
    records = {os.path.basename(r["input"]): r for r in doc["files"]}
    assert "cannot read" in records["c.exr"]["error"] and records["c.exr"]["maps"] == []
    for stem in ("a", "b"):
        record = records[f"{stem}.exr"]
        assert [m["layout"] for m in record["maps"]] == ["sphere", "latlong"]
        for entry in record["maps"]:
            (file,) = entry["files"]
            assert file["path"] == str(tmp_path / "out" / f"{stem}_{entry['layout']}.png")
            assert file["bit_depth"] == "uint8" and file["format"] == "png"
            _check_file(file, entry["layout"], entry["size"], 0)
        assert record["outputs"] == [m["files"][0]["path"] for m in record["maps"]]


@pytest.mark.parametrize("dry_run", [True, False])
def test_run_json_of_a_graph_file(tmp_path, dry_run):
    _source(tmp_path / "sky.exr")
    graph = tmp_path / "g.toml"
    graph.write_text('inputs = ["sky.exr"]\n[[steps]]\nstep = "resample"\nto = "paraboloid"\n'
                     'size = 6\nguard = 1\n[[steps]]\nstep = "write"\npath = "o/{stem}.exr"\n')  # fmt: skip
    run = envconv("run", graph, "--json", *(["--dry-run"] if dry_run else []))
    doc = _document(run)
    assert (doc["command"], doc["dry_run"]) == ("run", dry_run)
    (record,) = doc["files"]
    (entry,) = record["maps"]
    path = str(tmp_path / "o" / "sky.exr")
    assert record["outputs"] == [path] and entry["files"][0]["path"] == path
    assert (entry["layout"], entry["size"], entry["guard"], entry["width"]) == ("paraboloid", 6,
                                                                                1, 16)  # fmt: skip
    if dry_run:
        assert record["status"] == "planned" and not (tmp_path / "o").exists()
        assert entry["files"][0]["bytes"] is None
    else:
        _check_file(entry["files"][0], "paraboloid", 6, 1)
