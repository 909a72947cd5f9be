"""The table of known directions in docs/geometry.md, read from the page itself, so that the
tests check the contract as users read it (tests/test_layouts.py) and the page cannot drift
from the code."""

from __future__ import annotations

import re
from pathlib import Path

__all__ = ["DOC", "AXES", "TOP", "BOTTOM", "RIM", "OUTSIDE", "known_directions"]

DOC = Path(__file__).resolve().parent.parent / "docs" / "geometry.md"
#: The table's columns, in order: the six axes and q.
AXES = {
    "+X": (1.0, 0.0, 0.0),
    "-X": (-1.0, 0.0, 0.0),
    "+Y": (0.0, 1.0, 0.0),
    "-Y": (0.0, -1.0, 0.0),
    "+Z": (0.0, 0.0, 1.0),
    "-Z": (0.0, 0.0, -1.0),
    "q": (0.48, 0.6, 0.64),
}
TOP, BOTTOM, RIM = "top row", "bottom row", "rim"
OUTSIDE = "outside"  # a view's default field of view does not see it
_HEADING = "## Where known directions land (u, v)"
_POINT = re.compile(r"\(\s*([-\d.]+)\s*,\s*([-\d.]+)\s*\)")


def _entry(cell: str):
    """(u, v); a list of (u, v) that are all right ("(0, 0.5) = (1, 0.5)"); or a word."""
    cell = cell.strip()
    if cell in (TOP, BOTTOM, RIM, OUTSIDE):
        return cell
    points = [(float(u), float(v)) for u, v in _POINT.findall(cell)]
    if not points or _POINT.sub("", cell).replace("=", "").strip():
        raise ValueError(f"docs/geometry.md: cannot read the table entry {cell!r}")
    return points[0] if len(points) == 1 else points


def known_directions() -> dict[str, list]:
    """Layout name → the seven entries of its row (+X, −X, +Y, −Y, +Z, −Z, q)."""
    text = DOC.read_text("utf-8")
    section = text[text.index(_HEADING) :]
    rows = [line for line in section.splitlines() if line.startswith("|")]
    header = [c.strip().replace("−", "-") for c in rows[0].strip("|").split("|")]
    if header != ["layout", *AXES]:
        raise ValueError(f"docs/geometry.md: unexpected table header {header}")
    table = {}
    for line in rows[2:]:
        cells = line.strip().strip("|").split("|")
        table[cells[0].strip()] = [_entry(c) for c in cells[1:]]
    return table
