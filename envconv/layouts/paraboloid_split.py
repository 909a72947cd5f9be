"""paraboloid-split: the dual paraboloid as two N × N files, ``{face}`` = front and back.

::

    env_{face}.exr  ->  env_front.exr (z >= 0)    env_back.exr (z < 0)

Geometry exactly as :mod:`envconv.layouts.paraboloid`; in memory the halves sit side by side
as in the packed layout, and each file is one (guard-grown) cell.
"""

from .base import FAMILY_PARABOLOID, Cell, Layout

__all__ = ["LAYOUT"]

LAYOUT = Layout(
    name="paraboloid-split",
    family=FAMILY_PARABOLOID,
    description="dual paraboloid as two N x N files front/back, path needs {face}",
    columns=2,
    rows=1,
    aspect=1,
    cells=(Cell(0, 0, 0), Cell(1, 0, 1)),
    face_names=("front", "back"),
    multi_file=True,
)
