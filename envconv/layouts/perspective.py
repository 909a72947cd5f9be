"""perspective: a rectilinear (pinhole) view, py360convert's ``e2p``; W × H, N the height.

::

    u=0                                   u=1     looking from the centre along the view axis
    +-------------------------------------+ v=0   (yaw = pitch = roll = 0: +Z, the lat-long's
    |                 +Y                  |       centre), +Y up, image right -X: unmirrored
    |                  ^                  |
    |     +X  <------- +Z -------> -X     |       straight lines stay straight; the image
    |                  v                  |       plane spans the horizontal field of view
    |                 -Y                  |       across its width and the vertical one down
    +-------------------------------------+ v=1   its height, edge to edge

With a = 2u - 1, b = 2v - 1, t_x = tan(fov_h / 2) and t_y = tan(fov_v / 2): view direction
normalise(-a t_x, -b t_y, 1), then the view frame C of :mod:`envconv.layouts.view` (yaw turns
the view right, pitch raises it, roll banks it right, as an aircraft's and as ffmpeg's).
Inverse: with v = Cᵀ d in front of the camera (v_z > 0), (a, b) = (-v_x, -v_y) / (v_z t).

Options (:meth:`Layout.configure`, ``--fov H[,V] --yaw --pitch --roll``, ``--size W×H``): the
fields of view in degrees, each in (0, 180); default 90 across. With one angle the vertical
one follows from the image's aspect (square pixels); with two and no W×H the aspect follows
from them. ``N`` (``--size N``) is the height. Recorded in the file's ``envconv:view``.

py360convert's ``e2p(e, fov_deg, u_deg, v_deg, out_hw, in_rot_deg)`` makes the same view from
the same lat-long (its centre is the view's +Z, its pixel centres at ((i + 0.5)/W, (j + 0.5)/H)
as envconv's), and its ``u_deg``, ``v_deg``, ``in_rot_deg`` are envconv's yaw, pitch and roll.
One convention differs: its field of view spans the outermost pixel *centres* (it puts
``linspace(-tan, tan, W)`` on them), envconv's the image's edges, so py360convert's fov_deg
F is envconv's ``2 atan(W/(W-1) · tan(F/2))`` across W pixels (likewise down H). ffmpeg v360's
``flat`` (``h_fov``, ``v_fov``, ``yaw``, ``pitch``, ``roll``) is envconv's view as it stands.

Valid region: the whole W × H cell. A perspective view covers part of the sphere
(``partial``): read as a source, the directions outside its frustum are holes. Solid angle per
unit (a, b) area: t_x t_y / |(a t_x, b t_y, 1)|³. Continued mapping: the image plane past its
edges.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from .base import FAMILY_PERSPECTIVE, Cell, Layout
from .view import angle, fields_of_view, frame

__all__ = ["LAYOUT", "DEFAULT_FOV", "configure", "fields"]

#: The horizontal field of view without ``--fov``, degrees.
DEFAULT_FOV = 90.0


def fields(layout: Layout) -> tuple[float, float]:
    """(horizontal, vertical) field of view of a perspective layout, degrees: a single given
    angle is the horizontal one, the vertical following from the aspect (square pixels)."""
    fov = layout.view_options["fov"]
    if isinstance(fov, tuple):
        return fov
    half = math.tan(math.radians(fov) / 2.0) / float(layout.aspect)
    return fov, math.degrees(2.0 * math.atan(half))


def configure(
    layout: Layout,
    fov: Any = None,
    yaw: Any = None,
    pitch: Any = None,
    roll: Any = None,
    width: int | None = None,
    height: int | None = None,
) -> Layout:
    """``layout`` with these view options and size (None keeps the current value); see the
    module docstring. UsageError for a bad value."""
    view = layout.view_options
    aspect = layout.aspect
    if fov is not None:
        h, v = fields_of_view(fov, 180.0, pair=True)
        view["fov"] = h if v is None else (h, v)
        if v is not None and width is None:
            aspect = math.tan(math.radians(h) / 2.0) / math.tan(math.radians(v) / 2.0)
    if width is not None and height is not None:
        aspect = int(width) / int(height)  # round(aspect * height) is width again
    for name, value in (("yaw", yaw), ("pitch", pitch), ("roll", roll)):
        if value is not None:
            view[name] = angle(name, value)
    layout = replace(layout, aspect=aspect, view=tuple(view.items()))
    h, v = fields(layout)
    scales = (math.tan(math.radians(h) / 2.0), math.tan(math.radians(v) / 2.0))
    params = (*scales, *frame(view["yaw"], view["pitch"], view["roll"]), 1.0)
    return replace(layout, params=params)


LAYOUT = configure(
    Layout(
        name="perspective",
        family=FAMILY_PERSPECTIVE,
        description="perspective view W x H (py360convert e2p): --fov H[,V] (90), --size WxH, "
        "aimed with --yaw --pitch --roll",
        columns=1,
        rows=1,
        aspect=1,
        cells=(Cell(0, 0, 0),),
        face_names=("perspective",),
        view=(("fov", DEFAULT_FOV), ("yaw", 0.0), ("pitch", 0.0), ("roll", 0.0)),
        partial=True,
        configurer=configure,
    )
)
