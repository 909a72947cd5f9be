"""The fault suite: hostile inputs, arguments and faults, each proven to fail cleanly.

Each case states its expectation through tests/hostile.py: exit 2 for usage and 1 for a
run-time failure, one line on stderr, no traceback, nothing on stdout, no temporary files left,
inputs and old outputs untouched. Sections are grouped by what is attacked.
"""

from __future__ import annotations

import numpy as np
from conftest import write_plain
from hostile import assert_failed_cleanly, assert_untouched, envconv, snapshot

# --- outputs onto inputs ---------------------------------------------------------------------


def test_convert_refuses_to_write_onto_its_input(tmp_path):
    source = tmp_path / "sky.exr"
    write_plain(source, np.ones((8, 16, 3), np.float32))
    before = snapshot(source)
    run = envconv("convert", source, source, "--to", "cube-vcross", "--size", "4")
    assert_failed_cleanly(run, run.returncode, tmp_path, message="input")
    assert run.returncode in (1, 2)
    assert_untouched(before)
