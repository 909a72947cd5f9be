"""envconv.engine.globs: ``**`` walks each real folder once; elsewhere a glob is glob's.

Truth: trees of real folders, files and links made by the test, and ``glob.glob`` itself
wherever no link to a folder is involved.
"""

from __future__ import annotations

import glob
import os

from envconv.engine.globs import glob_files


def _touch(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"")
    return path


def test_without_folder_links_it_matches_glob(tmp_path, monkeypatch):
    for name in ("a.exr", "b.hdr", "x/c.exr", "x/y/d.exr", "x/y/z/e.exr", ".h/f.exr", "x/.g.exr"):
        _touch(tmp_path / name)
    os.symlink("a.exr", tmp_path / "x" / "link.exr")
    for pattern in ("**/*.exr", "x/**/*.exr", "x/**", "*/**/z/*.exr", "**/y/**/*.exr", "*.exr",
                    "x/*/*.exr", "**/nothing.exr"):  # fmt: skip
        for base in (str(tmp_path), None):
            full = pattern if base is None else os.path.join(base, pattern)
            if base is None:
                monkeypatch.chdir(tmp_path)
            expected = {os.path.abspath(p) for p in glob.glob(full, recursive=True)
                        if os.path.isfile(p)}  # fmt: skip
            assert {os.path.abspath(p) for p in glob_files(full)} == expected, full


def test_folder_links_are_followed_once_and_cycles_end(tmp_path):
    _touch(tmp_path / "tree" / "a" / "one.exr")
    _touch(tmp_path / "outside" / "two.exr")
    os.symlink("..", tmp_path / "tree" / "a" / "up")  # a cycle
    os.symlink("../outside", tmp_path / "tree" / "b")  # a folder outside the tree
    os.symlink("../tree/a", tmp_path / "outside" / "back")  # reached twice: named once
    found = glob_files(str(tmp_path / "tree" / "**" / "*.exr"))
    assert found == [
        str(tmp_path / "tree" / "a" / "one.exr"),
        str(tmp_path / "tree" / "b" / "two.exr"),
    ]
    assert glob_files(str(tmp_path / "missing" / "**" / "*.exr")) == []
