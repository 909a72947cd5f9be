"""Accuracy of the GGX chain at the IBL bench's size, against brute-force integrals.

    python benchmarks/ibl_accuracy.py          # with the python of the build to measure

Two measurements, levels 1-4 of a cube-faces 256 chain (gltf roughness, alpha = 1/64 ... 1/4),
and for the analytic skies also their irradiance on a 32 cube (α = 1: E/π):

1. ``analytic``: a 2048 x 1024 lat-long of tests/analytic.py's smooth sky, and of half of it
   plus a bright disk (tests/test_ibl.py's), against tests/ggx_reference.py's quadrature at 120
   random texels a level plus the 30 nearest the disk (relative RMS, max relative error).
2. ``park``: the bench's own map (benchmarks/bench.py's park lat-long at 2048 x 1024), against
   a direct sum of the lobe over every texel of the chain's level 0 (6 x 256^2 texels, 3 x 3
   sub-samples each, radiance uniform in a texel, which is what the prefilter reads), at the
   centres of 40 random texels a level and the 20 nearest the map's brightest texel (the chain's
   levels 1-4 take one sample a texel here, at its centre).

Run it with each build's python to compare builds; nothing here is a test.
"""

from __future__ import annotations

import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "tests"))
sys.path.insert(0, HERE)

import analytic  # noqa: E402
import naive  # noqa: E402
from ggx_reference import disk_environment, ggx_reference, texel_mean  # noqa: E402

import envconv  # noqa: E402

N = 256
LEVELS = (1, 2, 3, 4)
SUN = analytic.SUN / np.linalg.norm(analytic.SUN)


def _texels(size, count, rng, near=None, nearest=30):
    every = np.stack(np.meshgrid(np.arange(6), np.arange(size), np.arange(size), indexing="ij"),
                     -1).reshape(-1, 3)  # fmt: skip
    pick = every[rng.choice(len(every), min(count, len(every)), replace=False)]
    if near is not None:
        centres = texel_mean(lambda d: d, size, every, samples=1)
        pick = np.concatenate([pick, every[np.argsort(-(centres @ near))[:nearest]]])
    return pick


def _at(level, size, texels):
    faces = level.reshape(size, 6, size, -1)
    return faces[texels[:, 1], texels[:, 0], texels[:, 2]][:, :3].astype(np.float64)


def _report(name, k, alpha, got, truth):
    rms = np.sqrt(((got - truth) ** 2).sum() / (truth**2).sum())
    worst = (np.abs(got - truth) / np.abs(truth)).max()
    print(f"{name} level {k} alpha {alpha:.4f}: rms {rms * 100:.3f}%, max {worst * 100:.3f}%",
          flush=True)  # fmt: skip


def analytic_case():
    base = lambda d: 0.5 * analytic.smooth_radiance(d)  # noqa: E731
    radiance, disk = disk_environment(base, SUN, 0.08, [60.0, 50.0, 40.0])
    for name, fn, smooth, dk in (("smooth", analytic.smooth_radiance, analytic.smooth_radiance,
                                  None), ("disk", radiance, base, disk)):  # fmt: skip
        pixels = naive.pixel_average("latlong", 1024, fn, samples=2).astype(np.float32)
        chain = envconv.convert(envconv.EnvMap(pixels, "latlong"), "cube-faces", size=N,
                                mips="ggx")  # fmt: skip
        rough = [float(r) for r in chain.metadata["envconv:roughness"].split()]
        rng = np.random.default_rng(11)
        for k in LEVELS:
            size, alpha = N >> k, rough[k] ** 2
            texels = _texels(size, 120, rng, None if dk is None else dk[0])
            truth = texel_mean(lambda d, a=alpha, s=smooth, c=dk: ggx_reference(d, a, s, c), size,
                               texels)  # fmt: skip
            _report(f"analytic {name}", k, alpha, _at(chain.levels[k], size, texels), truth)
        # The irradiance map (E/π: the lobe with α = 1) of a 32 cube.
        irr = envconv.convert(envconv.EnvMap(pixels, "latlong"), "cube-faces", size=32,
                              irradiance=True)  # fmt: skip
        texels = _texels(32, 200, rng, None if dk is None else dk[0])
        truth = texel_mean(lambda d, s=smooth, c=dk: ggx_reference(d, 1.0, s, c), 32, texels)
        _report(f"analytic {name} irradiance", 0, 1.0, _at(irr.pixels, 32, texels), truth)


def park_case():
    from bench import _latlong

    source = _latlong(1024)
    chain = envconv.convert(source, "cube-faces", size=N, mips="ggx")
    rough = [float(r) for r in chain.metadata["envconv:roughness"].split()]
    level0 = chain.levels[0].reshape(N, 6, N, -1)[..., :3].astype(np.float64)
    sub = 3
    o = (np.arange(sub) + 0.5) / sub
    j, i = np.meshgrid(np.arange(N), np.arange(N), indexing="ij")
    dirs, weights, radiance = [], [], []
    for f in range(6):
        for u in o:
            for v in o:
                a, b = -1 + 2 * (i + u) / N, -1 + 2 * (j + v) / N
                dirs.append(naive.face_to_dir("cube", np.full(a.shape, f), a, b).reshape(-1, 3))
                weights.append((naive.face_density("cube", f, a, b) * (2 / N / sub) ** 2).ravel())
                radiance.append(level0[:, f].reshape(-1, 3))
    dirs, weights = np.concatenate(dirs), np.concatenate(weights)
    radiance = np.concatenate(radiance)
    brightest = dirs[np.argmax(radiance.sum(1))]

    def lobe_mean(n, alpha):
        a2 = alpha * alpha
        t = dirs @ n
        q = 1 + 0.5 * (a2 - 1) * (1 + t)
        k = np.where(t > 0, a2 * t / (math.pi * q * q), 0.0) * weights
        return (k[:, None] * radiance).sum(0) / k.sum()

    rng = np.random.default_rng(5)
    for k in LEVELS:
        size, alpha = N >> k, rough[k] ** 2
        texels = _texels(size, 40, rng, brightest, nearest=20)
        f, row, col = texels.T
        centres = naive.face_to_dir("cube", f, -1 + 2 * (col + 0.5) / size,
                                    -1 + 2 * (row + 0.5) / size)  # fmt: skip
        truth = np.array([lobe_mean(np.asarray(n, np.float64), alpha) for n in centres])
        _report("park", k, alpha, _at(chain.levels[k], size, texels), truth)


if __name__ == "__main__":
    print(f"envconv {envconv.__version__} ({os.path.dirname(envconv.__file__)})")
    analytic_case()
    park_case()
