"""fisheye: an equidistant fisheye view, ffmpeg v360's ``fisheye``; N × N, the disk valid.

::

    u=0                         u=1        looking from the centre along the view axis
    +---------------------------+  v=0     (yaw = pitch = roll = 0: +Z, the lat-long's
    |          .-'''-.          |          centre), +Y up, image right -X: unmirrored
    |       .'   +Y    '.       |
    |      /             \\      |          the angle from the axis grows linearly with
    |     |  +X   +Z   -X |     |          the radius: fov/2 at the rim (R = 1)
    |      \\             /      |
    |       '.   -Y    .'       |          default fov 180: the front hemisphere, its
    |          '-...-'          |          rim the great circle z = 0
    +---------------------------+  v=1

With X = 2u - 1, Y = 1 - 2v, R = |(X, Y)| and h = fov/2 in radians: θ = h R from the view
axis, view direction (-sin θ · X/R, sin θ · Y/R, cos θ), then the view frame C of
:mod:`envconv.layouts.view` (an aircraft's yaw, pitch and roll, as ffmpeg's: the view turns
right, rises, banks right). Inverse: with v = Cᵀ d, θ = atan2(|(v_x, v_y)|, v_z), R = θ / h,
(X, Y) = R · (-v_x, v_y) / |(v_x, v_y)|.

This is ffmpeg v360's ``fisheye`` output (``fisheye_to_xyz`` with ``h_fov = v_fov = fov`` on a
square frame; its default fov is 180 too) with its "front" at the lat-long's centre: ffmpeg
and envconv make the same picture from the same lat-long file. ffmpeg fills the corners past
the rim with the same formula; envconv gives them the continued mapping with a guard ring or
``--guard fill``, and alpha 0.

Options (:meth:`Layout.configure`, ``--fov``, ``--yaw``, ``--pitch``, ``--roll``): ``fov`` the
circle's diameter in degrees, 0 < fov <= 360 (360: the whole sphere, the rim the point behind;
the angular light probe mirrored left to right). Recorded in the file's ``envconv:view``.

Valid region: the disk R <= 1. A fisheye of fov < 360 covers part of the sphere (``partial``):
read as a source, the directions past its rim are holes. Solid angle per unit (a, b) area:
h |sin(h R)| / R, h² at the centre. Continued mapping: the same formula past R = 1.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from ..errors import UsageError
from .base import FAMILY_FISHEYE, Cell, Layout
from .view import angle, fields_of_view, frame

__all__ = ["LAYOUT", "DEFAULT_FOV", "configure"]

#: ffmpeg's default field of view for a fisheye (``h_fov = v_fov = 180``).
DEFAULT_FOV = 180.0


def configure(
    layout: Layout,
    fov: Any = None,
    yaw: Any = None,
    pitch: Any = None,
    roll: Any = None,
    width: int | None = None,
    height: int | None = None,
) -> Layout:
    """``layout`` with these view options (None keeps the current value); see the module
    docstring. UsageError for a bad value, or for a width other than the height."""
    if width is not None and height is not None and width != height:
        raise UsageError(f"fisheye is N x N; got a size of {width}x{height} (pass --size N)")
    view = layout.view_options
    if fov is not None:
        view["fov"] = fields_of_view(fov, 360.0, pair=False)[0]
    for name, value in (("yaw", yaw), ("pitch", pitch), ("roll", roll)):
        if value is not None:
            view[name] = angle(name, value)
    half = math.radians(view["fov"]) / 2.0
    params = (half, half, *frame(view["yaw"], view["pitch"], view["roll"]), 1.0)
    return replace(layout, params=params, view=tuple(view.items()), partial=view["fov"] < 360.0)


LAYOUT = configure(
    Layout(
        name="fisheye",
        family=FAMILY_FISHEYE,
        description="equidistant fisheye N x N (ffmpeg v360 fisheye): --fov (180), aimed with "
        "--yaw --pitch --roll",
        columns=1,
        rows=1,
        aspect=1,
        cells=(Cell(0, 0, 0),),
        face_names=("fisheye",),
        view=(("fov", DEFAULT_FOV), ("yaw", 0.0), ("pitch", 0.0), ("roll", 0.0)),
        configurer=configure,
    )
)
