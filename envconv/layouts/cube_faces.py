"""cube-faces: six N × N files, one per GL face, named with ``{face}`` in the path.

::

    sky_{face}.exr  ->  sky_px.exr  sky_nx.exr  sky_py.exr  sky_ny.exr  sky_pz.exr  sky_nz.exr
                        +X_c        -X_c        +Y_c        -Y_c        +Z_c        -Z_c

Faces follow the GL/D3D/KTX table of :mod:`envconv.layouts.cube` (px is world -X, as a
D3D/Unity/KTX cube map expects). In memory the faces sit side by side as in cube-hstrip; each
file is one (guard-grown) cell.
"""

from .base import FAMILY_CUBE_GL, Cell, Layout
from .cube import FACE_NAMES

__all__ = ["LAYOUT"]

LAYOUT = Layout(
    name="cube-faces",
    family=FAMILY_CUBE_GL,
    description="six N x N files px nx py ny pz nz (GL/D3D/KTX faces), path needs {face}",
    columns=6,
    rows=1,
    aspect=1,
    cells=tuple(Cell(i, 0, i) for i in range(6)),
    face_names=FACE_NAMES,
    multi_file=True,
)
