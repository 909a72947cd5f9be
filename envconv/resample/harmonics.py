"""Order-2 spherical harmonics of an environment and the irradiance they imply.

Ramamoorthi & Hanrahan, "An Efficient Representation for Irradiance Environment Maps",
SIGGRAPH 2001: the irradiance E(n) of a convex Lambertian surface with normal n is, to about
1% on average (3% at worst), the order-2 (9-coefficient) truncation of the environment's
spherical-harmonic expansion convolved with the clamped cosine.

Conventions
-----------
Basis (R&H eq. 3): real, orthonormal over the sphere (∫ Y_i Y_j dω = δ_ij), in the order
(l, m) = (0,0) (1,-1) (1,0) (1,1) (2,-2) (2,-1) (2,0) (2,1) (2,2), as polynomials of the unit
direction (x, y, z) in envconv's world frame (+Y up, +Z the lat-long centre, right-handed):

    Y00 = 0.282095                Y2-2 = 1.092548 x y
    Y1-1 = 0.488603 y             Y2-1 = 1.092548 y z
    Y10 = 0.488603 z              Y20 = 0.315392 (3 z² − 1)
    Y11 = 0.488603 x              Y21 = 1.092548 x z
                                  Y22 = 0.546274 (x² − y²)

(the constants are √(1/4π), √(3/4π), √(15/4π), √(5/16π), √(15/16π)). ``frame="cube"`` evaluates
them on the left-handed cube frame of DDS/KTX2/Direct3D/Unity instead, (−x, y, z), which
flips the sign of the terms odd in x (Y11, Y2-2, Y21).

Coefficients ``L_lm = ∫ L(ω) Y_lm(ω) dω`` (radiance × sr). Irradiance coefficients (R&H eq. 7–9)
``E_lm = Â_l L_lm`` with Â_0 = π, Â_1 = 2π/3, Â_2 = π/4, and ``E(n) = Σ E_lm Y_lm(n)``, or the
quadratic form ``E(n) = (n, 1)ᵀ M (n, 1)`` of R&H eq. 12. A Lambertian surface of albedo ρ
reflects radiance ρ E(n) / π.
"""

from __future__ import annotations

import math

import numpy as np

from ..envmap import EnvMap
from ..errors import UsageError
from ..layouts.geometry import kernel_geometry
from . import kernels

__all__ = [
    "BASIS",
    "BASIS_CONSTANTS",
    "COSINE_LOBE",
    "sh_basis",
    "project",
    "irradiance_coefficients",
    "irradiance_matrix",
    "sh_record",
]

#: (l, m) of each coefficient, in storage order.
BASIS = ((0, 0), (1, -1), (1, 0), (1, 1), (2, -2), (2, -1), (2, 0), (2, 1), (2, 2))
#: The polynomial of each basis function, for documentation and JSON output.
BASIS_POLYNOMIALS = ("1", "y", "z", "x", "x*y", "y*z", "(3*z^2-1)", "x*z", "(x^2-y^2)")
BASIS_CONSTANTS = (
    0.5 * math.sqrt(1 / math.pi),
    math.sqrt(3 / (4 * math.pi)),
    math.sqrt(3 / (4 * math.pi)),
    math.sqrt(3 / (4 * math.pi)),
    0.5 * math.sqrt(15 / math.pi),
    0.5 * math.sqrt(15 / math.pi),
    0.25 * math.sqrt(5 / math.pi),
    0.5 * math.sqrt(15 / math.pi),
    0.25 * math.sqrt(15 / math.pi),
)
#: Â_l of the clamped cosine per coefficient (R&H eq. 8–9): π, 2π/3 (×3), π/4 (×5).
COSINE_LOBE = np.array([math.pi] + [2 * math.pi / 3] * 3 + [math.pi / 4] * 5)


def _frame_dirs(dirs: np.ndarray, frame: str) -> np.ndarray:
    if frame == "world":
        return dirs
    if frame == "cube":
        return dirs * np.array([-1.0, 1.0, 1.0])
    raise UsageError(f"frame must be 'world' or 'cube', got {frame!r}")


def sh_basis(dirs, frame: str = "world") -> np.ndarray:
    """The nine basis functions at unit directions (..., 3): (..., 9) float64."""
    d = _frame_dirs(np.asarray(dirs, np.float64), frame)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    c = BASIS_CONSTANTS
    return np.stack([np.full_like(x, c[0]), c[1] * y, c[2] * z, c[3] * x, c[4] * x * y,
                     c[5] * y * z, c[6] * (3 * z * z - 1), c[7] * x * z, c[8] * (x * x - y * y)],
                    -1)  # fmt: skip


def project(envmap: EnvMap, frame: str = "world") -> np.ndarray:
    """The nine SH coefficients L_lm of every channel of ``envmap``: (9, C) float64.

    Each pixel's value is its solid-angle mean (docs/geometry.md), so the projection sums
    value × ∫_pixel Y_lm dω over the pixels of the valid region; the integrals take 2 × 2
    sub-samples per pixel (1 from N = 512 on), each weighted by its solid angle, and 16 × 16
    in pixels that the edge of the valid region cuts. Guard rings are skipped, and a direction
    that two cells both show (tennisball's overlap) counts in the cell that owns it.

    Examples
    --------
    >>> import numpy as np, envconv
    >>> from envconv.resample.harmonics import project
    >>> sky = envconv.EnvMap(np.ones((32, 64, 1), np.float32), "latlong")
    >>> round(float(project(sky)[0, 0]), 4)  # ∫ Y00 dω = √(4π)
    3.5449
    """
    sign = {"world": 1.0, "cube": -1.0}.get(frame)
    if sign is None:
        raise UsageError(f"frame must be 'world' or 'cube', got {frame!r}")
    samples = 2 if envmap.size < 512 else 1
    geometry = kernel_geometry(envmap.layout, envmap.size, envmap.guard)
    return kernels.sh_project(envmap.pixels, geometry, samples, sign)


def irradiance_coefficients(coefficients: np.ndarray) -> np.ndarray:
    """E_lm = Â_l L_lm (R&H eq. 7): the irradiance's own SH coefficients, (9, C)."""
    return COSINE_LOBE[:, None] * np.asarray(coefficients, np.float64)


def irradiance_matrix(coefficients: np.ndarray) -> np.ndarray:
    """R&H eq. 12's symmetric 4 × 4 matrices M, one per channel: (C, 4, 4), with
    E(n) = (x, y, z, 1) M (x, y, z, 1)ᵀ in the frame the coefficients were projected in."""
    L = np.asarray(coefficients, np.float64)
    c1, c2, c3, c4, c5 = 0.429043, 0.511664, 0.743125, 0.886227, 0.247708
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = L
    m = np.array([
        [c1 * L22, c1 * L2m2, c1 * L21, c2 * L11],
        [c1 * L2m2, -c1 * L22, c1 * L2m1, c2 * L1m1],
        [c1 * L21, c1 * L2m1, c3 * L20, c2 * L10],
        [c2 * L11, c2 * L1m1, c2 * L10, c4 * L00 - c5 * L20],
    ])  # fmt: skip
    return np.moveaxis(m, -1, 0)


def sh_record(envmap: EnvMap, frame: str = "world") -> dict:
    """Everything ``envconv sh`` prints: the basis, the radiance coefficients L_lm, the
    irradiance coefficients E_lm = Â_l L_lm and R&H's matrices M, per channel."""
    coefficients = project(envmap, frame)
    names = list(envmap.channels)
    return {
        "frame": {
            "world": "envconv world: right-handed, +Y up, +Z the lat-long centre",
            "cube": "cube (DDS/KTX2/Direct3D): left-handed, +Y up, +Z forward, +X right",
        }[frame],  # fmt: skip
        "basis": {
            "order": [f"l={deg},m={m}" for deg, m in BASIS],
            "functions": [
                f"{c:.9f}*{p}" for c, p in zip(BASIS_CONSTANTS, BASIS_POLYNOMIALS, strict=True)
            ],
            "normalisation": "real spherical harmonics, orthonormal over the sphere "
            "(Ramamoorthi & Hanrahan 2001, eq. 3)",
        },  # fmt: skip
        "channels": names,
        "radiance": {
            "units": "radiance x sr: L_lm = integral of L(w) Y_lm(w) dw",
            "coefficients": coefficients.tolist(),
        },  # fmt: skip
        "irradiance": {
            "units": "E(n) = sum_lm E_lm Y_lm(n); E_lm = A_l L_lm, A = pi, 2pi/3, pi/4 (R&H eq. 7-9)",
            "coefficients": irradiance_coefficients(coefficients).tolist(),
            "matrix": {
                "note": "E(n) = (x, y, z, 1) M (x, y, z, 1)^T (R&H eq. 12), per channel",
                "M": irradiance_matrix(coefficients).tolist(),
            },  # fmt: skip
        },
    }
