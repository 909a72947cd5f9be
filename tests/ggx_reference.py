"""Brute-force references for the GGX prefilter (envconv.resample.ibl), independent of envconv.

``ggx_reference`` integrates L(l) D(h) (n·l)⁺ over the sphere for each direction n, with a
deterministic quadrature in the half-vector h distributed as GGX (θ_h from the GGX CDF at
Gauss–Legendre nodes, φ uniform): ∫ g(l) D(h)(n·l)⁺ dl = E_h[g(l) (n·l)⁺ 4], h ~ D(h)(n·h).
A disk of constant radiance is integrated separately over the disk (polar Gauss grid), so
its edge costs no accuracy. ``texel_mean`` averages a function of direction over cube-face
texels with S × S solid-angle-weighted sub-samples (tests/naive.py's cube table).
"""

from __future__ import annotations

import naive
import numpy as np

__all__ = ["ggx_reference", "disk_environment", "texel_mean", "lobe_integral_at"]


def _frame(n):
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    up = np.where(np.abs(n[..., 1:2]) < 0.9, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
    t = np.cross(up, n)
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    return n, t, np.cross(n, t)


def _lobe(n, dirs, alpha):
    """D(h) (n·l)⁺ for directions n (m, 3) against l (k, 3): (m, k)."""
    a2 = alpha * alpha
    h = n[:, None, :] + dirs[None]
    nh2 = (h * n[:, None, :]).sum(-1) ** 2 / np.maximum((h**2).sum(-1), 1e-300)
    d = a2 / (np.pi * (nh2 * (a2 - 1) + 1) ** 2)
    return d * np.clip(n @ dirs.T, 0, None)


def lobe_integral_at(n, dirs, weights, alpha):
    """Σ_k w_k D(h) (n·l_k)⁺ for point-like pieces of radiance (m, k) → (m,)."""
    return _lobe(np.asarray(n, np.float64), np.asarray(dirs, np.float64), alpha) @ weights


def disk_environment(base, centre, radius, power):
    """base(d) plus ``power`` inside the disk of angular ``radius`` about ``centre``."""
    centre = np.asarray(centre, np.float64) / np.linalg.norm(centre)

    def radiance(d):
        d = np.asarray(d, np.float64)
        return base(d) + ((d @ centre) >= np.cos(radius))[..., None] * np.asarray(power)

    return radiance, (centre, radius, np.asarray(power, np.float64))


def ggx_reference(n, alpha, smooth, disk=None, n_xi=48, n_phi=48, n_r=32, n_psi=64):
    """Normalised GGX lobe integral of ``smooth`` (+ ``disk``) at unit directions n (m, 3)."""
    n, t, b = _frame(np.asarray(n, np.float64))
    xi, w_xi = np.polynomial.legendre.leggauss(n_xi)
    xi, w_xi = 0.5 * (xi + 1), 0.5 * w_xi
    phi = (np.arange(n_phi) + 0.5) / n_phi * 2 * np.pi
    a2 = alpha * alpha
    cos_t = np.sqrt((1 - xi) / (1 + (a2 - 1) * xi))
    sin_t = np.sqrt(1 - cos_t**2)
    local = [(sin_t[:, None] * np.cos(phi)).ravel(), (sin_t[:, None] * np.sin(phi)).ravel(),
             np.repeat(cos_t, n_phi)]  # fmt: skip
    w = np.repeat(w_xi, n_phi) / n_phi
    h = (
        local[0][None, :, None] * t[:, None]
        + local[1][None, :, None] * b[:, None]
        + (local[2][None, :, None] * n[:, None])
    )
    refl = 2 * local[2][None, :, None] * h - n[:, None]
    weight = w[None] * np.clip((refl * n[:, None]).sum(-1), 0, None) * 4
    num = (weight[..., None] * smooth(refl)).sum(1)
    if disk is not None:
        centre, radius, power = disk
        c, ct, cb = _frame(centre[None])
        r, w_r = np.polynomial.legendre.leggauss(n_r)
        r, w_r = 0.5 * radius * (r + 1), 0.5 * radius * w_r
        psi = (np.arange(n_psi) + 0.5) / n_psi * 2 * np.pi
        rr, pp = np.meshgrid(r, psi, indexing="ij")
        dirs = (
            np.cos(rr)[..., None] * c[0]
            + np.sin(rr)[..., None]
            * (np.cos(pp)[..., None] * ct[0] + np.sin(pp)[..., None] * cb[0])
        ).reshape(-1, 3)
        wl = (w_r[:, None] * np.sin(rr) * (2 * np.pi / n_psi)).ravel()
        num = num + lobe_integral_at(n, dirs, wl, alpha)[:, None] * power
    return num / weight.sum(1)[:, None]


def texel_mean(fn, size, texels, samples=4):
    """Solid-angle mean of fn(dirs (k, 3)) → (k, C) over cube-face texels (face, row, col)."""
    f, j, i = np.asarray(texels).T
    o = (np.arange(samples) + 0.5) / samples
    a = -1 + 2 * (i[:, None, None] + o[None, None, :]) / size
    b = -1 + 2 * (j[:, None, None] + o[None, :, None]) / size
    a, b = np.broadcast_arrays(a, b)
    faces = np.broadcast_to(f[:, None, None], a.shape)
    dirs = naive.face_to_dir("cube", faces, a, b).reshape(-1, 3)
    w = naive.face_density("cube", faces, a, b).reshape(len(f), -1)
    values = fn(dirs).reshape(len(f), samples * samples, -1)
    return (values * w[..., None]).sum(1) / w.sum(1)[:, None]
