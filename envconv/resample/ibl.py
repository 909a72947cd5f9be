"""Image-based lighting: GGX-prefiltered mip chains and the irradiance map.

Split-sum prefilter (Karis, "Real Shading in Unreal Engine 4", SIGGRAPH 2013), with N = V = R:
level 0 of a ``mips="ggx"`` chain is the mirror image; level k holds

    L_k(n) = ∫ L(l) D(h) (n·l)⁺ dl / ∫ D(h) (n·l)⁺ dl,   h = normalize(n + l),
    D(h) = α² / (π ((n·h)² (α² − 1) + 1)²),              α = r_k²,

each texel the solid-angle mean of L_k over its footprint, as every envconv pixel is. The
irradiance map (``irradiance=True``) is the same with α = 1, where D = 1/π: each texel holds
E(n)/π = (1/π) ∫ L(l) (n·l)⁺ dl, the radiance a white Lambertian surface reflects (multiply by
π for irradiance E).

Roughness per level (``roughness=``)
------------------------------------
With L levels and k = 0 … L−1 (level 0 is always the mirror, r = 0):

``gltf`` (default)
    r = k / (L − 1): Khronos glTF-IBL-Sampler (``lib/source/lib.cpp``, the GGX filter's
    ``roughness = lod / (mipLevelCount - 1)``).
``filament``
    r = 1 − √(1 − k/(L − 1)): Filament (``libs/iblprefilter/src/IBLPrefilterContext.cpp`` and
    cmgen's ``CubemapIBL``), ``lodToPerceptualRoughness(lod)`` = (√(a² + 4b·lod) − a)/(2b)
    with a = 2, b = −1, at lod = k/(L − 1); the inverse of lod = r (2 − r).
``unreal``
    r = min(1, 2^((1 − (L − 1 − k)) / 1.2)): Unreal Engine's ``ReflectionEnvironmentShared.ush``,
    ``GetReflectionCaptureRoughnessFromMip`` with REFLECTION_CAPTURE_ROUGHEST_MIP = 1 and
    REFLECTION_CAPTURE_ROUGHNESS_MIP_SCALE = 1.2 (the inverse of
    ``ComputeReflectionCaptureMipFromRoughness``), clamped to 1.
a list
    r_1 … r_{L−1} explicitly (level 0 stays the mirror), each in [0, 1].

In every mapping r is the perceptual roughness the engine's material uses, and α = r².

Method
------
The native core (``src/core/ibl.h``) sums the lobe over a pyramid of the source's cube faces
(Barnes–Hut): distant groups of texels enter through a second-order expansion of the lobe
about their luminance-weighted mean direction, so a one-texel sun lands where it is and the
result has no sampling noise and no fireflies; near texels are summed one by one. Tiles of
output samples share the walk (``src/core/prefilter.cpp``). Each output
pixel averages S × S point evaluations, S chosen so that they are at most α (and 1/8
rad) apart. The irradiance pyramid is binned from the source's pixels (:func:`_bin_plan`:
exact energy, a one-pixel sun at its own direction, any layout). A GGX chain's pyramid is its
own level 0 when that is a power-of-two cube without guard ring; otherwise the source is
resampled onto a power-of-two cube first.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from ..envmap import EnvMap
from ..errors import UsageError
from ..layouts import Layout, get_layout
from ..layouts.base import FAMILY_CUBE_GL
from ..layouts.geometry import horizon_pitch, kernel_geometry
from . import kernels
from .options import ROUGHNESS_MAPPINGS, check_roughness

__all__ = [
    "ROUGHNESS_MAPPINGS",
    "roughness_levels",
    "parse_roughness",
    "ggx_levels",
    "irradiance_levels",
    "irradiance_reads_level0",
]

log = logging.getLogger(__name__)

#: Expansion step bound (see src/core/ibl.h): looser for narrow lobes, where most texels are.
#: Set against brute-force integrals (benchmarks/ibl_accuracy.py; nodes brighter than the mean
#: are held tighter in the core): at 2.4 for the narrow lobes every level of the bench's chain
#: errs at most 0.38 % RMS and 0.75 % at worst, against the issue's 1 % and 5 %; 1.6 took 40 %
#: longer for level 1 for errors of 0.31 % and 0.73 % (docs/ibl.md).
_TAU_NARROW, _TAU_BROAD, _NARROW_ALPHA = 2.4, 0.5, 0.1
_MAX_SAMPLES = 8
_MAX_PYRAMID = 2048
#: Texels of the finest level near n's horizon are integrated by 3 x 3 sub-samples: at 32 they
#: are small enough for that to be exact to ~1e-3 even for the broad lobes.
_MIN_PYRAMID = 32
#: The cosine lobe is broad: a 64 cube resolves it, and each node's luminance-weighted mean
#: direction still places a small sun exactly.
_IRRADIANCE_PYRAMID = 64
#: At most this many points are binned into the irradiance pyramid (_bin_plan): an 8192 × 4096
#: lat-long (33.5 M, about 0.6 s on 2 cores); larger maps are resampled onto the cube.
_MAX_BIN_POINTS = 1 << 26


def roughness_levels(mapping, count: int) -> list[float]:
    """Perceptual roughness r_k of levels 0 … count−1 (r_0 = 0, the mirror); see the module doc.

    Examples
    --------
    >>> roughness_levels("gltf", 5)
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    if count < 1:
        raise UsageError("a chain has at least one level")
    last = max(count - 1, 1)
    if isinstance(mapping, str):
        if mapping == "gltf":
            return [k / last for k in range(count)]
        if mapping == "filament":
            return [1.0 - math.sqrt(max(0.0, 1.0 - k / last)) if k else 0.0 for k in range(count)]
        if mapping == "unreal":
            return [0.0] + [min(1.0, 2.0 ** ((1 - (count - 1 - k)) / 1.2)) for k in range(1, count)]
        raise UsageError(f"unknown roughness mapping {mapping!r}; choose one of "
                         f"{', '.join(ROUGHNESS_MAPPINGS)} or give a list")  # fmt: skip
    values = [float(v) for v in mapping]
    if len(values) != count - 1:
        raise UsageError(f"the chain has {count - 1} levels after the mirror, but "
                         f"{len(values)} roughness values were given")  # fmt: skip
    if any(not 0.0 <= v <= 1.0 for v in values):
        raise UsageError("roughness values must lie in [0, 1]")
    return [0.0] + values


def parse_roughness(value):
    """A mapping name, or a list of floats from ``"0.1,0.2,…"`` (the CLI's --roughness) or a
    list; the check of :func:`envconv.resample.options.check_roughness`."""
    return check_roughness(value)


def _pow2(n: float) -> int:
    return 1 << max(0, math.ceil(math.log2(max(n, 1.0))))


def _pyramid_size(to: Layout, size: float, alphas, cap=None) -> int:
    """Face size p of the pyramid for lobes ``alphas`` on an output of ``size``: a power of two
    at least the output's own cube resolution and about 2/α for the narrowest lobe."""
    n_cube = size * horizon_pitch("cube-faces") / horizon_pitch(to)
    narrowest = min((a for a in alphas if a > 0), default=1.0)
    p = _pow2(max(n_cube, min(2.0 / narrowest, 2.0 * n_cube)))
    return min(max(p, _MIN_PYRAMID), cap or _MAX_PYRAMID)


def _reads_level0(to: Layout, guard: int, level0_height: int, p: int) -> bool:
    """Whether the pyramid is summed from the chain's own level 0 (a cube of p without guard
    ring) rather than from the source resampled onto a cube of p."""
    return to.family == FAMILY_CUBE_GL and guard == 0 and level0_height == to.rows * p


def irradiance_reads_level0(source: EnvMap, to, size: int, guard: int) -> bool:
    """Whether :func:`irradiance_levels` of ``source`` reads the resampled level 0's colour
    (else it needs only its shape and coverage, and the resampler may skip making it): only
    when the source is not binned and level 0 is a cube of the pyramid's own size."""
    to = get_layout(to)
    p = _pyramid_size(to, _irradiance_cube(to), [1.0], cap=_IRRADIANCE_PYRAMID)
    if _bin_plan(source, p) is not None:
        return False
    return _reads_level0(to, guard, to.image_size(size, guard)[1], p)


def _irradiance_cube(to: Layout) -> float:
    return _IRRADIANCE_PYRAMID * horizon_pitch(to) / horizon_pitch("cube-faces")


def _bin_plan(source: EnvMap, p: int) -> tuple[int, float] | None:
    """(points a pixel side, half a point's diagonal in radians) for binning the source's pixels
    straight into the irradiance pyramid of p, or None to resample the source onto the cube.

    A pixel becomes sub × sub points (16 × 16 where only part of it is owned: a disk's rim, a
    cell's edge), sub chosen so that points are at most 0.6 of the smallest level-0 texel (at
    the cube's corners, 0.44 of a face centre's) apart along an axis: every texel gathers
    several. Energy is then exact and a one-pixel sun keeps its direction. A source needing
    more than 4 × 4 points a pixel, or over _MAX_BIN_POINTS points in all, is resampled.

    The GGX chain's pyramid is not binned: at the bench's 2048 × 1024 → 256 it would need
    2 × 2 points a pixel (0.15 s, against none for summing the chain's own level 0), and
    the prefilter's own sampling of a narrow lobe (S from α) still moves a one-pixel sun's
    energy by ~10 % at the first levels (docs/ibl.md)."""
    if source.layout.name == "latlong" and source.guard == 0:
        height = source.pixels.shape[0]
        side = math.pi / height  # the largest pixel: at the equator, π/H square
    else:
        side = math.sqrt(2.0) * _largest_pixel_angle(source)
    smallest = 0.44 * (math.pi / 2) / p
    sub = max(1, math.ceil(side / (0.6 * smallest) - 1e-9))
    pixels = source.pixels.shape[0] * source.pixels.shape[1]
    if sub > 4 or pixels * sub * sub > _MAX_BIN_POINTS:
        return None
    return sub, side / sub


def _largest_pixel_angle(source: EnvMap, grid: int = 128) -> float:
    """The largest angle from a pixel's centre to its corners, over a grid × grid sample of the
    source's pixels (radians): half the diagonal of its largest pixels."""
    height, width = source.pixels.shape[:2]
    rows = np.unique(np.linspace(0, height - 1, min(grid, height)).round().astype(int))
    cols = np.unique(np.linspace(0, width - 1, min(grid, width)).round().astype(int))
    j, i = np.meshgrid(rows + 0.5, cols + 0.5, indexing="ij")
    offsets = [(0.0, 0.0), (-0.49, -0.49), (0.49, -0.49), (-0.49, 0.49), (0.49, 0.49)]
    points = np.stack([np.stack([i + dx, j + dy], -1).reshape(-1, 2) for dx, dy in offsets])
    geometry = kernel_geometry(source.layout, source.size, source.guard)
    dirs, flags = kernels.map_points_to_dirs(geometry, points.reshape(-1, 2))
    dirs, flags = dirs.reshape(5, -1, 3), flags.reshape(5, -1)
    valid = (flags == 2).all(axis=0)
    if not valid.any():
        return math.pi
    cos = np.clip((dirs[1:, valid] * dirs[0, valid]).sum(-1), -1.0, 1.0)
    return float(np.arccos(cos).max() / 0.98)  # the corners were 0.49 of a pixel out, not 0.5


def _pyramid(
    source: EnvMap,
    to: Layout,
    size: int,
    guard: int,
    rot,
    level0,
    alphas,
    cap=None,
    bin_source=False,
):
    """(pyramid, p, channels, rotation) for the prefilter: with ``bin_source`` (the irradiance
    pyramid) the source binned into a p-cube where :func:`_bin_plan` allows, else the cube
    faces (6, p, p, C) of the chain's level 0 or of a resample, summed into the core's pyramid;
    ``rotation`` maps output directions to the pyramid's."""
    nch = level0.shape[2]
    p = _pyramid_size(to, size, alphas, cap)
    plan = _bin_plan(source, p) if bin_source else None
    if plan is not None:
        # Output direction d reads source direction rot d; a source pixel at s lands at rotᵀ s.
        to_pyramid = np.asarray(rot, np.float64).T
        if source.layout.name == "latlong" and source.guard == 0:
            pyramid = kernels.ibl_pyramid_binned(source.pixels, to_pyramid, p, plan[0])
        else:
            geometry = kernel_geometry(source.layout, source.size, source.guard)
            pyramid = kernels.ibl_pyramid_binned_any(source.pixels, geometry, to_pyramid, p,
                                                     *plan)  # fmt: skip
        if pyramid is not None:
            return pyramid, p, nch, np.eye(3)
    # A source meant for binning may have skipped level 0 (irradiance_reads_level0): if its
    # binning fails, it is resampled below rather than read from level 0.
    if plan is None and _reads_level0(to, guard, level0.shape[0], p):
        from ..io.textures import cube_faces

        faces = np.stack(cube_faces(to, level0))
        rotation = np.eye(3)
    else:
        mosaic = np.empty((p, 6 * p, nch), np.float32)
        no_rips = np.zeros((1, 1, nch), np.float32)
        kernels.resample_rows(
            source.pixels, no_rips, 0, 0, kernel_geometry(source.layout, source.size, source.guard),
            kernel_geometry("cube-faces", p, 0), 1.0, 1.0, 0, kernels.FILTER_BILINEAR,
            np.ascontiguousarray(rot, np.float64), False, mosaic,
        )  # fmt: skip
        faces = mosaic.reshape(p, 6, p, nch).transpose(1, 0, 2, 3)
        rotation = np.eye(3)
    return kernels.ibl_pyramid(faces), p, nch, rotation


def _prefilter(pyr, to: Layout, size: int, guard: int, fill: bool, shape, scale, alpha, rotation):
    p, nch = pyr[1], pyr[2]
    height, width = shape
    pitch = horizon_pitch(to) / size * max(scale)
    spacing = min(max(alpha, 1e-3), 0.125)
    samples = int(min(_MAX_SAMPLES, max(1, math.ceil(pitch / spacing))))
    tau = _TAU_NARROW if alpha <= _NARROW_ALPHA else _TAU_BROAD
    out = np.empty((height, width, nch), np.float32)
    kernels.ibl_prefilter(pyr[0], p, nch, kernel_geometry(to, size, guard), scale[0], scale[1],
                          alpha, samples, pyr[3], fill, tau, out)  # fmt: skip
    log.debug("prefilter %dx%d alpha=%.4g S=%d tau=%.2g from a %d cube", width, height,
              alpha, samples, tau, p)  # fmt: skip
    return out


def ggx_levels(source: EnvMap, to, size: int, guard: int, fill: bool, rot, chain, roughness):
    """The chain with levels 1 … of ``chain`` (a list of (pixels, coverage), level 0 first, as
    :func:`envconv.resample.mips.build_chain` returns it) replaced by the GGX prefilter of ``source``,
    and the roughness of every level. ``rot`` maps output directions to source directions."""
    to = get_layout(to)
    rough = roughness_levels(parse_roughness(roughness), len(chain))
    alphas = [r * r for r in rough]
    pyr = _pyramid(source, to, size, guard, rot, chain[0][0], alphas[1:])
    out = [chain[0]]
    w0, h0 = chain[0][0].shape[1], chain[0][0].shape[0]
    for k in range(1, len(chain)):
        pixels, coverage = chain[k]
        scale = (w0 / pixels.shape[1], h0 / pixels.shape[0])
        if alphas[k] <= 0.0:
            out.append((pixels, coverage))
            continue
        level = _prefilter(pyr, to, size, guard, fill, pixels.shape[:2], scale, alphas[k], pyr[3])
        out.append((level, coverage))
    return out, rough


def irradiance_levels(source: EnvMap, to, size: int, guard: int, fill: bool, rot, chain):
    """Every level of ``chain`` replaced by E/π, the clamped-cosine convolution (α = 1)."""
    to = get_layout(to)
    pyr = _pyramid(
        source,
        to,
        _irradiance_cube(to),
        guard,
        rot,
        chain[0][0],
        [1.0],
        cap=_IRRADIANCE_PYRAMID,
        bin_source=True,
    )
    w0, h0 = chain[0][0].shape[1], chain[0][0].shape[0]
    out = []
    for pixels, coverage in chain:
        scale = (w0 / pixels.shape[1], h0 / pixels.shape[0])
        out.append((_prefilter(pyr, to, size, guard, fill, pixels.shape[:2], scale, 1.0, pyr[3]),
                    coverage))  # fmt: skip
    return out
