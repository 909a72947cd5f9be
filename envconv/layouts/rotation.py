"""Rotations of the environment, ``--rotate YAW,PITCH,ROLL`` in degrees.

The environment is turned about +Y by YAW, then about +X by PITCH, then about +Z by ROLL, each by
the right-hand rule in the world frame (+Y up, +Z the lat-long centre, +X at u = 0.25). A
positive yaw therefore carries what was at +Z towards +X: in a lat-long it slides to the left.
The rotated environment is L'(d) = L(Rᵀ d) with R = Rz(roll) · Rx(pitch) · Ry(yaw).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import UsageError

__all__ = ["rotation_matrix", "parse_rotation"]


def rotation_matrix(yaw: float = 0.0, pitch: float = 0.0, roll: float = 0.0) -> np.ndarray:
    """3×3 matrix R that turns the environment (see module docstring); angles in degrees."""
    cy, sy = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    cp, sp = math.cos(math.radians(pitch)), math.sin(math.radians(pitch))
    cr, sr = math.cos(math.radians(roll)), math.sin(math.radians(roll))
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cp, -sp], [0.0, sp, cp]])
    rz = np.array([[cr, -sr, 0.0], [sr, cr, 0.0], [0.0, 0.0, 1.0]])
    return rz @ rx @ ry


def parse_rotation(value: str | Sequence[float] | None) -> tuple[float, float, float]:
    """Parse ``"YAW,PITCH,ROLL"`` (degrees; missing trailing values are 0)."""
    if value is None:
        return (0.0, 0.0, 0.0)
    if isinstance(value, str):
        parts = [p for p in value.replace(" ", "").split(",") if p != ""]
    else:
        parts = list(value)
    if not 1 <= len(parts) <= 3:
        raise UsageError(f"rotate expects YAW,PITCH,ROLL in degrees, got {value!r}")
    try:
        angles = [float(p) for p in parts]
    except ValueError:
        raise UsageError(
            f"rotate expects numbers YAW,PITCH,ROLL in degrees, got {value!r}"
        ) from None
    if not all(math.isfinite(a) for a in angles):
        raise UsageError(f"rotate angles must be finite, got {value!r}")
    return tuple(angles + [0.0] * (3 - len(angles)))  # type: ignore[return-value]
