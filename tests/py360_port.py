"""py360convert's ``e2p`` (perspective view of a lat-long), re-expressed in numpy as a reference.

Nothing here calls envconv. py360convert (github.com/sunset1995/py360convert, MIT) needs SciPy
for its rotations and its sampler, which the test extra does not carry, so its perspective path
is restated here, read from py360convert 1.0.4 (``py360convert/e2p.py`` and ``utils.py``:
``xyzpers``, ``rotation_matrix``, ``xyz2uv``, ``uv2coor``, ``EquirecSampler``).
tests/test_perspective.py checks this port against py360convert itself where it is installed.

- ``e2p(e_img, fov_deg, u_deg, v_deg, out_hw, in_rot_deg)``: one fov → h_fov = v_fov; u =
  −radians(u_deg) (so + looks right), v = radians(v_deg) (+ up), in_rot = radians(in_rot_deg).
- ``xyzpers``: a grid (x, −y, 1) with x = ``linspace(−tan(h/2), tan(h/2), W)`` and y likewise:
  the outermost pixel *centres* sit at the field of view's edges. Row vectors are turned as
  ``xyz · Rx(v) · Ry(u) · Ri`` where Ri turns by in_rot about ``[0, 0, 1] · Rx · Ry``, each R
  scipy's ``Rotation.from_rotvec(angle · axis).as_matrix()`` (a right-handed turn). float32.
- ``xyz2uv``: u = atan2(x, z), v = atan2(y, |(x, z)|); ``uv2coor``: x = (u/2π + 0.5) W − 0.5,
  y = (−v/π + 0.5) H − 0.5: its lat-long's centre is +z, +x at three quarters, +y up.
- ``EquirecSampler`` (no OpenCV): the image padded by one pixel (top and bottom rows the
  edge rows rolled by W/2, columns wrapped), coordinates + 1, ``map_coordinates(order=1)``:
  bilinear.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["e2p", "rotation_matrix"]


def rotation_matrix(rad: float, axis) -> np.ndarray:
    """scipy's ``Rotation.from_rotvec(rad · axis).as_matrix()``: Rodrigues' formula."""
    axis = np.asarray(axis, np.float64)
    angle = abs(rad) * np.linalg.norm(axis)
    if angle == 0.0:
        return np.eye(3)
    k = rad * axis / angle
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


def _xyzpers(h_fov, v_fov, u, v, out_hw, in_rot) -> np.ndarray:
    out = np.ones((*out_hw, 3), np.float32)
    x_max, y_max = np.tan(h_fov / 2), np.tan(v_fov / 2)
    x_rng = np.linspace(-x_max, x_max, num=out_hw[1], dtype=np.float32)
    y_rng = np.linspace(-y_max, y_max, num=out_hw[0], dtype=np.float32)
    out[..., :2] = np.stack(np.meshgrid(x_rng, -y_rng), -1)
    rx = rotation_matrix(v, (1.0, 0.0, 0.0))
    ry = rotation_matrix(u, (0.0, 1.0, 0.0))
    ri = rotation_matrix(in_rot, np.array([0, 0, 1.0]).dot(rx).dot(ry))
    return out.dot(rx).dot(ry).dot(ri).astype(np.float32)


def _padded(img: np.ndarray) -> np.ndarray:
    h, w = img.shape[:2]
    padded = np.empty((h + 2, w + 2, *img.shape[2:]), img.dtype)
    padded[1:-1, 1:-1] = img
    padded[0, 1:-1] = np.roll(img[0], w // 2, axis=0)
    padded[-1, 1:-1] = np.roll(img[-1], w // 2, axis=0)
    padded[:, 0] = padded[:, -2]
    padded[:, -1] = padded[:, 1]
    return padded


def _bilinear(img: np.ndarray, y: np.ndarray, x: np.ndarray) -> np.ndarray:
    y0 = np.clip(np.floor(y).astype(int), 0, img.shape[0] - 2)
    x0 = np.clip(np.floor(x).astype(int), 0, img.shape[1] - 2)
    ty, tx = (y - y0)[..., None], (x - x0)[..., None]
    return ((1 - ty) * ((1 - tx) * img[y0, x0] + tx * img[y0, x0 + 1])
            + ty * ((1 - tx) * img[y0 + 1, x0] + tx * img[y0 + 1, x0 + 1]))  # fmt: skip


def e2p(e_img, fov_deg, u_deg, v_deg, out_hw, in_rot_deg=0.0) -> np.ndarray:
    """py360convert.e2p(e_img, fov_deg, u_deg, v_deg, out_hw, in_rot_deg, mode="bilinear")
    of an (H, W, C) lat-long, as float64."""
    e_img = np.asarray(e_img, np.float64)
    h, w = e_img.shape[:2]
    if np.ndim(fov_deg) == 0:
        h_fov = v_fov = math.radians(float(fov_deg))
    else:
        h_fov, v_fov = math.radians(fov_deg[0]), math.radians(fov_deg[1])
    xyz = _xyzpers(h_fov, v_fov, -math.radians(u_deg), math.radians(v_deg), tuple(out_hw),
                   math.radians(in_rot_deg))  # fmt: skip
    x, y, z = xyz[..., 0], xyz[..., 1], xyz[..., 2]
    lon, lat = np.arctan2(x, z), np.arctan2(y, np.hypot(x, z))
    coor_x = (lon / (2 * np.pi) + 0.5) * w - 0.5
    coor_y = (-lat / np.pi + 0.5) * h - 0.5
    return _bilinear(_padded(e_img), coor_y.astype(np.float64) + 1, coor_x.astype(np.float64) + 1)
