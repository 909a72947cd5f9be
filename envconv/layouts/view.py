"""The view of an aimed layout (fisheye, perspective): field of view, direction, and its tag.

A view looks from the centre along its axis. With yaw, pitch and roll all 0 the axis is +Z (the
lat-long's centre), +Y is up and image right is −X: the picture is unmirrored, as the
lat-long's centre is seen from inside. The angles are an aircraft's, in degrees, applied in
that order, each about the view's own axes: ``yaw`` turns the view to the right (towards −X),
``pitch`` raises it (towards +Y), ``roll`` banks it to the right (clockwise as one looks along
it, so the picture turns counter-clockwise). ffmpeg v360's ``yaw``, ``pitch`` and ``roll`` are
the same (checked against ffmpeg in tests/test_fisheye.py). The view of an environment with
(yaw, pitch, roll) is the unturned view of that environment rotated by ``--rotate
YAW,PITCH,-ROLL`` (:mod:`envconv.layouts.rotation`): its frame is C = Rᵀ with
R = Rz(−roll) · Rx(pitch) · Ry(yaw), world direction = C · view direction.

A file records the view in one ``envconv:view`` attribute, e.g. ``fov=90,73.7398 yaw=30
pitch=-10 roll=0`` (degrees), so that it reads back as it was written (in an ImageDescription,
where words are separated by spaces, as ``envconv:view=fov=90;yaw=30;pitch=-10;roll=0``).
"""

from __future__ import annotations

import math
from typing import Any

from ..errors import UsageError
from .rotation import rotation_matrix

__all__ = ["VIEW_TAG", "frame", "angle", "fields_of_view", "view_text", "parse_view_text"]

#: The metadata attribute that records a view.
VIEW_TAG = "envconv:view"


def frame(yaw: float, pitch: float, roll: float) -> tuple[float, ...]:
    """The view frame C = Rᵀ (module docstring), row-major: 9 floats."""
    return tuple(float(x) for x in rotation_matrix(yaw, pitch, -roll).T.ravel())


def angle(name: str, value: Any) -> float:
    """``value`` as a finite angle in degrees, or UsageError naming the option."""
    try:
        result = float(value)
    except (TypeError, ValueError):
        raise UsageError(f"--{name} expects an angle in degrees, got {value!r}") from None
    if not math.isfinite(result):
        raise UsageError(f"--{name} must be finite, got {value!r}")
    return result


def fields_of_view(value: Any, largest: float, pair: bool) -> tuple[float, float | None]:
    """(horizontal, vertical or None) of ``--fov``: one angle, ``"H,V"`` or a pair of numbers,
    each in (0, largest) (``largest`` included when it is 360); UsageError otherwise, and for a
    pair when ``pair`` is False."""
    parts = [p for p in value.replace(" ", "").split(",")] if isinstance(value, str) else value
    if not isinstance(parts, (list, tuple)):
        parts = [parts]
    if not 1 <= len(parts) <= (2 if pair else 1):
        form = "H or H,V" if pair else "one angle (the circle's diameter)"
        raise UsageError(f"--fov expects {form} in degrees, got {value!r}")
    fovs = [angle("fov", p) for p in parts]
    for fov in fovs:
        if not (0.0 < fov < largest or (largest == 360.0 and fov == 360.0)):
            bound = "360 included" if largest == 360.0 else f"below {largest:g}"
            raise UsageError(f"--fov must be above 0 and {bound} degrees, got {fov:g}")
    return fovs[0], (fovs[1] if len(fovs) == 2 else None)


def view_text(view: dict[str, Any]) -> str:
    """The ``envconv:view`` value of a view: ``fov=H[,V] yaw=Y pitch=P roll=R``."""
    fov = view["fov"]
    fov_text = ",".join(f"{f:.10g}" for f in fov) if isinstance(fov, tuple) else f"{fov:.10g}"
    turns = " ".join(f"{k}={float(view[k]):.10g}" for k in ("yaw", "pitch", "roll"))
    return f"fov={fov_text} {turns}"


def parse_view_text(text: Any) -> dict[str, Any]:
    """The options of an ``envconv:view`` value (:func:`view_text`); UsageError when it is not
    one (a file's tag that cannot be read is named, not guessed)."""
    options: dict[str, Any] = {}
    for word in str(text).replace(";", " ").split():
        key, eq, value = word.partition("=")
        if not eq or key not in ("fov", "yaw", "pitch", "roll") or key in options:
            raise UsageError(f"{VIEW_TAG} {text!r} is not fov=H[,V] yaw=Y pitch=P roll=R")
        options[key] = value if key == "fov" else angle(key, value)
    return options
