"""equal-area: Clarberg's equal-area octahedral square, N × N, +Y at the centre.

::

    u=0, v=0                          u=1         the same places as the octahedral
      +-------------+-------------+               layout: +Y centre, the horizon on the
      | -Y        .'+Z`.        -Y|               diamond |a| + |b| = 1, -Y at every
      |         .'  |   `.        |               corner; seen from inside looking up,
      |       .'    |     `.      |               +Z at the top, unmirrored
      |     .'      |       `.    |
      |   .'        |         `.  |               but the polar angle follows the area:
      | -X ---------+Y---------+X |               every pixel subtends 4π/N² sr
      |   `.        |         .'  |
      |     `.      |       .'    |               a = 2u - 1 (right), b = 2v - 1 (down)
      |       `.    |     .'      |
      |         `.  |   .'        |               pbrt-v4 reads it with --in-convention
      | -Y        `.-Z.'        -Y|               pbrt (imgtool makeequiarea's files)
      +-------------+-------------+  v=1

The map (Clarberg, "Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD", JGT 13(3), 2008;
pbrt-v4 ``EqualAreaSquareToSphere`` in ``src/pbrt/util/math.cpp``), in the z-up frame t of the
paper: unfold the corner triangles first, (a, b) -> ((1 - |b|) sgn a, (1 - |a|) sgn b) where
|a| + |b| > 1, which marks the lower hemisphere. The unfolded point's L1 radius r = |a| + |b|
fixes the polar angle, t_z = ±(1 - r²) (the cap above t_z holds a share r² of the hemisphere,
as the diamond inside r holds a share r² of its area), and its place along the diamond's edge
fixes the azimuth, φ = (π/2) |b| / r within the quadrant of (sgn a, sgn b):
t = (r √(2 - r²) cos φ sgn a, r √(2 - r²) sin φ sgn b, ±(1 - r²)). envconv's direction is
d = (t_x, t_z, -t_y), as for the octahedral layout. Inverse: t = (d_x, -d_z, d_y),
r = hypot(t_x, t_y) / √(1 + |t_z|) (= √(1 - |t_z|) without its cancellation near the poles),
φ = atan2(|t_y|, |t_x|), b' = 2rφ/π, a' = r - b', folded back as (1 - b', 1 - a') where t_z < 0,
then signed by t_x and t_y.

One cell, N × N. Valid region: the whole square; no pixel is invalid, so alpha is 1 in every
pixel of the square. Continued mapping: the octahedral fold of :mod:`.octahedral`
((a, b) -> (2 - a, -b) past a = 1, and so on), which is pbrt-v4's ``WrapEqualAreaSquare``.
Solid angle per unit (a, b) area: π everywhere (4π over the area-4 square).

The ``pbrt`` preset (:mod:`envconv.layouts.conventions`) is pbrt-v4's own square: pixel (u, v), v from
the top row, holds EqualAreaSquareToSphere(u, v) in pbrt's z-up light frame, and a lat-long
is read there at (atan2(y, x)/2π mod 1, acos(z)/π), as ``imgtool makeequiarea`` does.
"""

from .base import FAMILY_EQUAL_AREA, Cell, Layout

__all__ = ["LAYOUT"]

LAYOUT = Layout(
    name="equal-area",
    family=FAMILY_EQUAL_AREA,
    description="equal-area octahedral N x N (Clarberg 2008, pbrt-v4): every pixel 4pi/N^2 sr",
    columns=1,
    rows=1,
    aspect=1,
    cells=(Cell(0, 0, 0),),
    face_names=("equal-area",),
)
