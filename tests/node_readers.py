"""Run the npm readers of tests/node (parse-dds, ktx-parse) on a file envconv wrote.

The readers are independent of envconv: they locate every image in a DDS or KTX2 file from
its header alone. Tests that use them are skipped only where node is not installed; where it
is, the packages are installed from tests/node/package-lock.json (``npm ci``) on first use.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess

import pytest

__all__ = ["read_container"]

NODE_DIR = os.path.join(os.path.dirname(__file__), "node")


def _ready() -> str:
    """node, with the packages installed; test processes running side by side (pytest-xdist)
    install them once, one at a time: a second ``npm ci`` or a read of a half-installed
    package made a reader fail with "Cannot find package"."""
    import fcntl

    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed: the DDS/KTX2 files cannot be read by npm readers")
    ready = os.path.join(NODE_DIR, "node_modules", ".envconv-installed")
    if os.path.exists(ready):
        return node
    with open(os.path.join(NODE_DIR, "package-lock.json"), "rb") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # held until the install is whole
        if not os.path.exists(ready):
            npm = shutil.which("npm")
            if npm is None:
                pytest.fail("node is installed but npm is not: cannot install tests/node")
            done = subprocess.run([npm, "ci", "--no-audit", "--no-fund"], cwd=NODE_DIR,
                                  capture_output=True, text=True, timeout=600)  # fmt: skip
            if done.returncode:
                pytest.fail(f"npm ci in tests/node failed: {done.stderr.strip()[-500:]}")
            with open(ready, "w") as marker:
                marker.write("npm ci done\n")
    return node


def read_container(path, out_bin) -> tuple[dict, bytes]:
    """(header fields as the reader reports them, bytes of the images it located)."""
    node = _ready()
    done = subprocess.run([node, os.path.join(NODE_DIR, "read_container.mjs"), str(path),
                           str(out_bin)], capture_output=True, text=True, timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    with open(out_bin, "rb") as handle:
        return json.loads(done.stdout), handle.read()
