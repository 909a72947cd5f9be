"""Sets of files replaced together (envconv.io.sets): all new or all old, whatever fails.

Truth: the bytes of every old file (read before the write), the constant each new map holds,
and the folder listings. A failing rename is injected (os.replace); a crash is a subprocess
SIGKILLed while it sleeps inside a rename, after a known number of them.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import envconv
from envconv.errors import ImageIOError
from envconv.io import sets

FACES = ("px", "nx", "py", "ny", "pz", "nz")


def _faces_map(value: float, n: int = 4):
    return envconv.EnvMap(np.full((n, 6 * n, 3), value, np.float32), "cube-faces")


def _state(folder) -> dict[str, bytes]:
    return {name: (folder / name).read_bytes() for name in sorted(os.listdir(folder))}


def _values(template) -> list[float]:
    pixels = envconv.read(str(template)).pixels
    n = pixels.shape[0]
    return [float(pixels[:, f * n : (f + 1) * n].mean()) for f in range(6)]


def _file_value(path) -> float:
    """The constant a file holds, read by OpenImageIO directly (no envconv, no protocol)."""
    import OpenImageIO as oiio

    return float(np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT)).mean())


def _failing_replace(monkeypatch, fail_at: int):
    """os.replace that fails (EPERM) on its ``fail_at``-th call onto a face file."""
    real, calls = os.replace, []

    def replace(src, dst, *args, **kwargs):
        if "sky_" in os.path.basename(dst) and not os.path.basename(dst).startswith("."):
            calls.append(dst)
            if len(calls) == fail_at:
                raise PermissionError(1, "Operation not permitted", dst)
        return real(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "replace", replace)
    return calls


@pytest.mark.parametrize("fail_at", [1, 4, 6])
def test_a_failed_rename_leaves_the_old_set_whole(tmp_path, monkeypatch, fail_at):
    envconv.write(_faces_map(1.0), tmp_path / "sky_{face}.exr")
    before = _state(tmp_path)
    _failing_replace(monkeypatch, fail_at)
    with pytest.raises(
        ImageIOError, match=r"cannot write .*sky_\w\w\.exr: Operation not permitted"
    ):
        envconv.write(_faces_map(2.0), tmp_path / "sky_{face}.exr")
    assert _state(tmp_path) == before  # the same six files, byte for byte, and nothing else


def test_a_failed_rename_of_a_new_set_leaves_nothing(tmp_path, monkeypatch):
    _failing_replace(monkeypatch, 3)
    with pytest.raises(ImageIOError):
        envconv.write(_faces_map(2.0), tmp_path / "sky_{face}.exr")
    assert os.listdir(tmp_path) == []


def test_a_failed_rename_of_level_files_in_face_folders(tmp_path, monkeypatch):
    """One file per face and level, each face in its own folder: 6 folders, 3 levels."""
    chain = envconv.convert(_faces_map(1.0, 8), "cube-faces", size=8, mips=3)
    template = tmp_path / "{face}" / "sky_{level}.exr"
    for face in FACES:
        (tmp_path / face).mkdir()
    envconv.write(chain, template)
    before = {face: _state(tmp_path / face) for face in FACES}
    assert all(len(files) == 3 for files in before.values())
    _failing_replace(monkeypatch, 10)
    with pytest.raises(ImageIOError):
        envconv.write(envconv.convert(_faces_map(2.0, 8), "cube-faces", size=8, mips=3), template)
    assert {face: _state(tmp_path / face) for face in FACES} == before


_CRASH = """
import os, sys, time
import numpy as np
import envconv
real, seen = os.replace, []
def replace(src, dst, *a, **k):
    real(src, dst, *a, **k)
    if ".tmp" in os.path.basename(src) and not os.path.basename(dst).startswith("."):
        seen.append(dst)
        if len(seen) == int(sys.argv[2]):
            print("renamed", flush=True)
            time.sleep(600)
os.replace = replace
env = envconv.EnvMap(np.full((4, 24, 3), 2.0, np.float32), "cube-faces")
envconv.write(env, sys.argv[1])
"""


@pytest.mark.parametrize("killed_after, expected", [(3, 1.0), (6, 2.0)])
def test_a_set_killed_mid_replacement_reads_whole(tmp_path, killed_after, expected):
    """SIGKILL after 3 of 6 renames: on disk the set is mixed, but envconv reads it only after
    repairing it from the journal, back to the old set; after all 6 (the journal not yet
    removed) forward to the new one. The repair leaves nothing behind."""
    template = tmp_path / "sky_{face}.exr"
    envconv.write(_faces_map(1.0), template)
    child = subprocess.Popen([sys.executable, "-c", _CRASH, str(template), str(killed_after)],
                             stdout=subprocess.PIPE, text=True)  # fmt: skip
    try:
        assert child.stdout.readline() == "renamed\n"
    finally:
        child.kill()
        child.wait()
    on_disk = [_file_value(tmp_path / f"sky_{f}.exr") for f in FACES]
    assert on_disk == [2.0] * killed_after + [1.0] * (6 - killed_after)  # mixed, or all new
    assert any(".tmp-journal" in name for name in os.listdir(tmp_path))
    assert _values(template) == pytest.approx([expected] * 6)
    assert sorted(os.listdir(tmp_path)) == sorted(f"sky_{f}.exr" for f in FACES)


def test_the_next_write_into_the_folder_repairs_a_dead_set(tmp_path):
    template = tmp_path / "sky_{face}.exr"
    envconv.write(_faces_map(1.0), template)
    child = subprocess.Popen([sys.executable, "-c", _CRASH, str(template), "2"],
                             stdout=subprocess.PIPE, text=True)  # fmt: skip
    try:
        assert child.stdout.readline() == "renamed\n"
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait()
    code = ("import sys, envconv, numpy as np\n"
            "env = envconv.EnvMap(np.ones((4, 8, 3), np.float32), 'latlong')\n"
            "envconv.write(env, sys.argv[1])\n")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code, str(tmp_path / "other.exr")],
                          capture_output=True, text=True)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "rolled back" in done.stderr
    assert sorted(os.listdir(tmp_path)) == sorted([*(f"sky_{f}.exr" for f in FACES), "other.exr"])
    assert _values(template) == pytest.approx([1.0] * 6)


def test_one_file_is_replaced_by_one_rename(tmp_path, monkeypatch):
    target = tmp_path / "one.exr"
    envconv.write(envconv.EnvMap(np.ones((4, 8, 3), np.float32), "latlong"), target)
    calls = []
    real = os.replace
    monkeypatch.setattr(os, "replace", lambda *a, **k: (calls.append(a), real(*a, **k))[1])
    monkeypatch.setattr(os, "link", lambda *a, **k: pytest.fail("no backup for one file"))
    envconv.write(envconv.EnvMap(np.zeros((4, 8, 3), np.float32), "latlong"), target)
    assert len(calls) == 1 and os.listdir(tmp_path) == ["one.exr"]
    assert sets.WAIT > 0
