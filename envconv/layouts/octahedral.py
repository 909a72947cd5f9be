"""octahedral: the octahedral encoding of Cigolle et al. 2014, N × N, +Y at the centre.

::

    u=0, v=0                          u=1         the sky seen from inside, looking up,
      +-------------+-------------+               with +Z (the lat-long centre) at the
      | -Y        .'+Z`.        -Y|               top: unmirrored
      |         .'  |   `.        |
      |       .'    |     `.      |               the diamond |a| + |b| <= 1 holds the
      |     .'      |       `.    |               upper hemisphere (y >= 0), its edge
      |   .'        |         `.  |               the horizon; the four corner
      | -X ---------+Y---------+X |               triangles hold the lower hemisphere,
      |   `.        |         .'  |               folded out over the diamond's edges
      |     `.      |       .'    |
      |       `.    |     .'      |               a = 2u - 1 (right), b = 2v - 1 (down)
      |         `.  |   .'        |
      | -Y        `.-Z.'        -Y|               every corner is -Y
      +-------------+-------------+  v=1

The map, in the papers' z-up frame t (Cigolle et al. 2014, "A Survey of Efficient
Representations for Independent Unit Vectors", JCGT 3(2); DDGI and RTXGI use the same code):
t = (a, b, 1 - |a| - |b|) inside the diamond, t = ((1 - |b|) sgn a, (1 - |a|) sgn b,
1 - |a| - |b|) outside it (sgn 0 = +1), then normalised. envconv's direction is
d = (t_x, t_z, -t_y): the papers' +Z (the centre) is +Y, their +X (right) is +X and their +Y
(down) is -Z. Inverse: t = (d_x, -d_z, d_y), (a, b) = (t_x, t_y) / (|t_x| + |t_y| + |t_z|),
folded the same way where t_z < 0.

One cell, N × N. Valid region: the whole square; no pixel is invalid, so alpha is 1 in every
pixel of the square. Continued mapping (guard rings, filter taps): the octahedral fold. The
two halves of each edge show the same directions, (1, b) and (1, -b) being one, so a point
past an edge is the point mirrored across that edge and across the edge's midpoint:
(a, b) -> (2 - a, -b) past a = 1, (-2 - a, -b) past a = -1, (-a, 2 - b) past b = 1,
(-a, -2 - b) past b = -1 (pbrt-v4's WrapEqualAreaSquare states the same rule in (u, v)). A
one-pixel guard ring is then exactly the border RTXGI's ProbeBorderUpdateCS copies around each
probe. Solid angle per unit (a, b) area: 1 / |t|³ before normalising, from 1 at the centre,
axes and corners to 3√3 at the middle of each octant.

Presets (:mod:`envconv.layouts.conventions`): ``ddgi`` (the DDGI/RTXGI encoding in a Y-up
right-handed world, so its centre is world +Z), ``ddgi-z-up`` (in a Z-up right-handed world,
centre up; envconv's own layout) and ``unreal`` (RTXGI in Unreal's Z-up left-handed world).
"""

from .base import FAMILY_OCTAHEDRAL, Cell, Layout

__all__ = ["LAYOUT"]

LAYOUT = Layout(
    name="octahedral",
    family=FAMILY_OCTAHEDRAL,
    description="octahedral N x N (Cigolle et al. 2014, DDGI): +Y centre, -Y corners",
    columns=1,
    rows=1,
    aspect=1,
    cells=(Cell(0, 0, 0),),
    face_names=("octahedral",),
)
