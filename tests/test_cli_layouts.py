"""``envconv layouts``: the world axis each cube face holds, and its turn, against the
known-direction table of docs/geometry.md and the cell tables of tests/naive.py."""

from __future__ import annotations

import math
import re

import naive
from conftest import run_cli
from geometry_doc import AXES, known_directions

from envconv.layouts import FAMILIES, get_layout


def _face_lines() -> dict[str, str]:
    result = run_cli(["layouts"])
    assert result.exit_code == 0, result.stderr
    block = result.stdout.split("\n\n")[1]
    return {
        line.split()[0]: line
        for line in block.splitlines()
        if not line.startswith(("world", "c ="))
    }


def test_every_cube_layout_names_the_world_axis_of_each_face_and_its_turn():
    table, lines = known_directions(), _face_lines()
    assert sorted(lines) == sorted(FAMILIES["cubemap"])
    for name in FAMILIES["cubemap"]:
        layout = get_layout(name)
        _, columns, rows, _, cells = naive.GRIDS[name]
        at = {(col, row): (face, turned) for col, row, face, turned in cells}
        expected = {}
        # The cell that holds each axis, from the table's (u, v), names the face that holds it.
        for axis, uv in zip(list(AXES)[:6], table[name][:6], strict=True):
            col = min(math.floor(uv[0] * columns), columns - 1)
            row = min(math.floor(uv[1] * rows), rows - 1)
            face, turned = at[(col, row)]
            expected[layout.face_names[face]] = (axis, turned)
        said = dict(re.findall(r"\b(px|nx|py|ny|pz|nz) ([+-][XYZ])", lines[name]))
        assert said == {face: axis for face, (axis, _) in expected.items()}, lines[name]
        turned = {face for face, (_, t) in expected.items() if t}
        assert set(re.findall(r"\b(\w\w) [+-][XYZ] \(turned 180 degrees\)", lines[name])) == turned
    # The GL faces hold the mirrored x axis: px is world -X (docs/geometry.md).
    assert "px -X" in lines["cube-faces"] and "px +X" in lines["cube-exr"]
