"""eac: the equi-angular cubemap of ffmpeg's v360 filter (``eac``) and YouTube, 3N × 2N.

::

    u=0            u=1/3           u=2/3            u=1
    +---------------+---------------+---------------+  v=0
    |      +X       |      +Z       |      -X       |  left, front, right: OpenEXR's faces,
    |  (left of +Z) | (lat-long     | (right of +Z) |  +Y up, one continuous band
    |               |  centre)      |               |
    +---------------+---------------+---------------+  v=1/2
    |      -Y       |      -Z       |      +Y       |  down, back, up: each turned a quarter
    | -Z at right,  | +Y at right,  | +Z at right,  |  turn, one continuous band
    | +X at bottom  | +X at bottom  | +X at bottom  |
    +---------------+---------------+---------------+  v=1

Face k sits in column k % 3, row k // 3, an N × N cell. Within a cell (a', b') ∈ [-1, 1]² (a'
right, b' down) are equal in angle: the cube face's plane coordinate is a = tan(π/4 · a'),
b = tan(π/4 · b') (inverse a' = (4/π) atan a), so every pixel spans the same angle along a row
through the face's centre. Direction before normalising:

    face 0  +X  (1, -b, a)      face 1  +Z  (-a, -b, 1)     face 2  -X  (-1, -b, -a)
    face 3  -Y  (b, -1, -a)     face 4  -Z  (b, a, -1)      face 5  +Y  (b, 1, a)

Direction → face by the major axis, ties to x, then y, then z (zero counting as positive), as
the cube layouts. This is ffmpeg v360's ``eac`` (libavfilter/vf_v360.c, ``prepare_eac_out``:
top row LEFT, FRONT, RIGHT unturned; bottom row DOWN ROT_270, BACK ROT_90, UP ROT_270) with
its "front" at the lat-long's centre, so ffmpeg and envconv write the same picture from the
same lat-long file. ffmpeg also pads every row with 2 fixed pixels (left and right of the row,
above and below it): its (3N + 4) × (2N + 8) image with those pixels cut out is envconv's.

Valid region: every pixel of the six cells. Solid angle per unit (a', b') area:
(π/4)² (1 + a²)(1 + b²) / (1 + a² + b²)^{3/2}, from 0.83 (mid-edge) to 1.18 (centre) times its
mean π/6 (the plain cube's varies by a factor of 5). Continued mapping (guard rings, filter taps): past |a'| = 1
the face's plane goes on at the edge's rate, a = ±(1 + π/2 (|a'| − 1)), which continues the
map smoothly (C1) to any distance.
"""

from .base import FAMILY_EAC, Cell, Layout

__all__ = ["LAYOUT", "FACE_NAMES"]

#: File-part names of the six faces, in face order (ffmpeg's names for them).
FACE_NAMES = ("left", "front", "right", "down", "back", "up")

LAYOUT = Layout(
    name="eac",
    family=FAMILY_EAC,
    description="equi-angular cubemap 3N x 2N (ffmpeg v360 eac, YouTube): +X +Z -X over -Y -Z +Y",
    columns=3,
    rows=2,
    aspect=1,
    cells=tuple(Cell(k % 3, k // 3, k) for k in range(6)),
    face_names=FACE_NAMES,
)
