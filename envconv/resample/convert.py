"""Convert an environment map from one layout to another: ``envconv.convert``.

Resampling is by inverse mapping. Every output pixel takes S×S stratified sub-samples; each is
mapped to a direction through the output layout, rotated, mapped into the source layout and
read through a seam-aware reconstruction filter. Samples are weighted by their solid angle, so
every output pixel is the solid-angle mean of the environment over its area and energy is
preserved.

Rules
-----
size (default)
    Keep the input's angular resolution at the horizon: ``N_out = round(N_in · k_out / k_in)``
    where ``k / N`` is a layout's mean pixel pitch (√ of the pixel solid angle) over the horizon
    circle (see :func:`envconv.layouts.geometry.horizon_pitch`; k = π for lat-long, ≈1.68 for cubes).
samples="auto"
    Adaptive, per pixel: a pixel whose edge spans ``f`` source pixels there takes
    ``clamp(ceil(2f - 3), 1, 32)`` sub-samples along that edge, measured along each axis (so
    a cube face read from a lat-long's polar rows, or an angular map's rim, gets them where it
    needs them). In a reduction sub-samples are about half a texel apart, so every texel under
    the pixel is read and nothing aliases, and a one-texel highlight keeps its energy. Up to
    f = 2 a pixel takes one sample: as sharp as a correct single-tap converter (one bilinear tap
    reads 2 × 2 texels, so no texel is skipped), since averaging bilinear taps there only blurs
    (pass ``samples=2`` or more to trade sharpness for exact highlight energy near 1:1). Pixels cut by a rim or a cell edge take at least 8 × 8.
    With the bilinear filter a lat-long source is read through a horizontal rip-map where a
    pixel spans at least 8 × 2^k texels along x (its polar rows), and sub-samples are counted
    in that level's texels (see :func:`envconv.resample.kernels.build_rips` and ``RIP_MIN_SPAN`` in
    :mod:`envconv.resample.kernels`). The rip-map is filled only in the rows next to each pole, at most
    a fifth of the source's bytes (:func:`rip_row_cap`, for the memory bound of
    docs/memory.md); elsewhere level 0 is read with up to 32 sub-samples per edge.
    A same-grid conversion (same layout, size and guard, no rotation) copies pixels exactly.
    With ``mips`` the whole chain uses one S, ``clamp(round(r), 1, 32)`` with ``r`` the ratio
    of output to source pixel pitch on the horizon, so that every level is the exact block
    average of level 0 (see :mod:`envconv.resample.mips`).
filter
    ``area`` (default: each pixel the exact solid-angle mean of the box-reconstructed source
    over its footprint, or of a conservative piecewise-linear reconstruction where the
    conversion magnifies (:func:`envconv.resample.options.magnifies`), docs/geometry.md "Pixel
    values"; the sample rules above are the point kernel's), ``bilinear``, ``bicubic`` (Catmull-Rom, clamped to the range of the four nearest
    texels so it can never ring past them: no new negatives next to an HDR highlight) or
    ``nearest``. With a guard ring the area filter makes the cells' pixels and, around a
    whole-sphere layout, a bilinear tap of that map the ring's; around a partial view the ring
    is more of the view, each pixel the exact mean over its own footprint under the continued
    mapping (:func:`_area_with_guard`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace

import numpy as np

from ..envmap import EnvMap
from ..errors import LayoutError, UsageError
from ..layouts import Layout, get_layout
from ..layouts.conventions import apply_remap, environment_axes, resolve_convention
from ..layouts.geometry import kernel_geometry, pixel_pitch
from ..layouts.rotation import parse_rotation, rotation_matrix
from ..limits import check_size
from . import kernels
from .holes import VALID_CHANNEL
from .options import (
    FILTERS,
    MAX_SAMPLES,
    auto_samples,
    check_conventions,
    check_guard,
    check_mips,
    check_samples,
    choose_filter,
    default_size,
    magnifies,
    output_channels,
    output_layout,
    rim_to_mirror_ball,
    ring_past_antipode,
)
from .regrid import output_on_grid, source_on_centres

__all__ = ["convert", "default_size", "auto_samples", "source_rips", "rip_row_cap",
           "memory_needed", "FILTERS", "MAX_SAMPLES"]  # fmt: skip

log = logging.getLogger(__name__)


def convert(
    envmap: EnvMap,
    to: Layout | str,
    size: int | None = None,
    samples: int | str | None = "auto",
    filter: str | None = None,
    rotate=None,
    guard: int | str = 0,
    alpha: bool = False,
    mips: bool | int | str | None = None,
    roughness="gltf",
    irradiance: bool = False,
    in_convention=None,
    out_convention=None,
    up: str | None = None,
    axes: str | None = None,
    fov=None,
    yaw: float | None = None,
    pitch: float | None = None,
    roll: float | None = None,
    threads: int | None = None,
) -> EnvMap:
    """Resample ``envmap`` into layout ``to``.

    Parameters
    ----------
    envmap : EnvMap
        The source. All its channels are resampled (an alpha channel is carried like colour).
    to : str or Layout
        Output layout name, e.g. ``"cube-vcross"``.
    size : int, str or (int, int), optional
        Output characteristic size N (docs/geometry.md, "Sizes"). Default: the N that keeps
        the source's pixel pitch along the horizon (an aimed layout's: at its view axis),
        rounded with ``mips`` so that every level holds whole cells
        (:func:`envconv.resample.options.default_size`). A perspective view also takes
        ``"WxH"`` or (W, H).
    samples : int or "auto"
        Sub-samples per pixel edge S (S×S per pixel).
    filter : {"area", "bilinear", "bicubic", "nearest"}, optional
        ``area``: each pixel the exact solid-angle mean of the box-reconstructed source over
        its footprint (every texel's energy kept; piecewise linear where the output is 1.5 ×
        finer than the source, by solid angle); the others read the source at sub-sample
        points through that filter. Default: ``area`` (a fisheye guard ring that reaches the
        point behind the view, where the continued map folds, is point-sampled around the
        view's exact pixels: :func:`envconv.resample.options.choose_filter`).
    rotate : "YAW,PITCH,ROLL" or 3 numbers, optional
        Rotation of the environment in degrees (see :mod:`envconv.layouts.rotation`).
    guard : int or "fill"
        Guard-ring width G in pixels, or ``"fill"`` to give every pixel the continued mapping
        of its nearest cell.
    alpha : bool
        Add (or replace) an alpha channel holding each pixel's valid-region coverage.
    mips : bool, int or str, optional
        Also build a mip chain (``EnvMap.levels``): True (or 0) for the full round-down chain
        down to 1 × 1, K for at most K levels. See :mod:`envconv.resample.mips`. ``"ggx"`` (or
        ``"ggx:K"``) prefilters levels 1 … with the GGX lobe of the split-sum approximation
        instead of box-averaging them (:mod:`envconv.resample.ibl`).
    roughness : str or list of float
        With ``mips="ggx"``: the roughness of each level, ``gltf`` (r = k/(L−1)), ``filament``,
        ``unreal`` or the list r_1 … r_{L−1}. Recorded as ``envconv:roughness`` metadata.
    irradiance : bool
        Write E/π, the clamped-cosine convolution of the environment (every level of a
        chain), instead of the environment itself.
    in_convention, out_convention : str or (3, 3) array, optional
        Convention of the tool that made the input / will read the output: a preset name
        (``blender``, ``cmft``, ``skylibs``, ``unity``, ``unreal``, ``ffmpeg``, …), an axis
        remap such as ``"-x,z,y"`` or a matrix. See :mod:`envconv.layouts.conventions`.
    up : {"y", "z"}, optional
        Up axis of the input's world; ``"z"`` turns its +Z into +Y (same as ``axes="x,z,-y"``).
    axes : str, optional
        Signed axis permutation applied to the input's environment, e.g. ``"-x,z,y"``.
    fov, yaw, pitch, roll : optional
        The view of an aimed output layout (fisheye, perspective; see
        :mod:`envconv.layouts.view`): ``fov`` in degrees (a fisheye's diameter, 180 by default;
        a perspective view's horizontal angle or ``"H,V"``, 90 by default); ``yaw`` turns the
        view right, ``pitch`` raises it, ``roll`` banks it right (an aircraft's angles, as
        ffmpeg v360's). Other layouts refuse them.
    threads : int, optional
        Threads of the native core for this call (default: the process setting,
        :func:`envconv.resample.kernels.set_threads`); other threads' calls keep their own.

    Returns
    -------
    EnvMap
        float32 pixels in the new layout; metadata is carried over.

    Examples
    --------
    >>> import numpy as np, envconv
    >>> sky = envconv.EnvMap(np.ones((64, 128, 3), np.float32), "latlong")
    >>> cube = envconv.convert(sky, to="cube-vcross", size=32)
    >>> cube.pixels.shape
    (128, 96, 3)
    """
    to, size = output_layout(envmap, to, size, fov, yaw, pitch, roll, out_convention, mips, guard)
    filter = choose_filter(filter)
    options = dict(size=size, samples=samples, filter=filter, rotate=rotate, guard=guard,
                   alpha=alpha, mips=mips, roughness=roughness, irradiance=irradiance,
                   in_convention=in_convention, out_convention=out_convention, up=up, axes=axes)  # fmt: skip
    with kernels.threads_for(threads):
        _check_memory(envmap, to, size, guard, mips, alpha, samples, filter, out_convention)
        if envmap.layout.partial:
            from .partial import pad_partial

            envmap = pad_partial(envmap)
        if rim_to_mirror_ball(envmap, to, filter):
            envmap = convert(envmap, "latlong", size=round(1.5 * default_size(envmap, "latlong")),
                             in_convention=in_convention)  # fmt: skip
            options["in_convention"] = None
        if envmap.valid is not None or envmap.parts:
            from .holes import convert_with_holes

            return convert_with_holes(envmap, to, _resample, **options)
        return _resample(envmap, to, **options)


#: Working bytes per thread of the area filter, for the memory estimate.
AREA_SCRATCH = 12 << 20


def _resample(
    envmap,
    to,
    size,
    samples,
    filter,
    rotate,
    guard,
    alpha,
    mips,
    roughness,
    irradiance,
    in_convention,
    out_convention,
    up,
    axes,
) -> EnvMap:
    """:func:`convert` of a map without holes or parts."""
    to = get_layout(to)
    mips, ggx = _mip_filter(mips)
    cin, cout = check_conventions(to, out_convention, mips, envmap.layout, in_convention, guard)
    # Sample grids (mitsuba, openexr-edges): resampled on envconv's centres (.regrid).
    envmap = source_on_centres(envmap, None if in_convention is None else cin)
    if cin.remap is not None:
        envmap = replace(
            envmap, pixels=apply_remap(envmap.layout, envmap.pixels, envmap.guard, cin.remap)
        )
    fill = guard == "fill"
    guard_px = 0 if fill else check_guard(guard)
    if filter not in FILTERS:
        raise UsageError(f"unknown filter {filter!r}; choose one of {', '.join(FILTERS)}")
    if size is None:
        size = default_size(envmap, to, cout, mips=_chain_request(mips, ggx), guard=guard)
    if not isinstance(size, (int, np.integer)) or size < 1:
        raise LayoutError(f"size must be a positive integer, got {size!r}")
    size = check_size(size)
    n_samples = check_samples(samples)
    if n_samples is None and filter == "area":
        # The area filter integrates each pixel exactly: one piece per pixel is the exact mean
        # (and every mip level, a weighted block mean of level 0, is exact too).
        n_samples = 1
    if n_samples is None and mips:
        n_samples = auto_samples(envmap, to, size)
    if n_samples is None and irradiance:
        # Every level becomes the cosine convolution, read from the source itself: of level 0
        # only the coverage is kept, and 8 x 8 sub-samples give it as "auto" does at a rim
        # (auto would take up to 32 x 32 per pixel in a strong reduction, for nothing).
        n_samples = kernels.AUTO_EDGE_SAMPLES
    yaw, pitch, roll = parse_rotation(rotate)
    # Output direction d → source direction Rᵀ d.
    rot = rotation_matrix(yaw, pitch, roll).T
    # Conventions (envconv.layouts.conventions): d_source = M_inᵀ Aᵀ Rᵀ M_out d.
    rot = cin.matrix.T @ environment_axes(up, axes).T @ rot @ cout.matrix
    rot = np.ascontiguousarray(rot)

    width, height = to.image_size(size, guard_px)
    src = envmap.pixels
    alpha_index = envmap.alpha_index
    # An appended alpha channel of a single level is the kernel's coverage, written in place.
    direct_alpha = alpha and alpha_index is None and not (mips or ggx or irradiance)
    # Zeroed (np.zeros maps fresh pages lazily): the kernel then never touches the empty cells.
    out = np.zeros((height, width, src.shape[2] + int(direct_alpha)), np.float32)
    same_grid = (
        to == envmap.layout
        and size == envmap.size
        and guard_px == envmap.guard
        and n_samples in (None, 1)
        and np.array_equal(rot, np.eye(3))
    )
    # The coverage is kept for an alpha channel, the GGX and irradiance chains and the
    # same-grid copy below (a plain chain needs only the weights).
    needs_coverage = alpha or same_grid or (mips and (ggx or irradiance))
    coverage = None
    if direct_alpha:
        coverage = out[:, :, -1]
    elif needs_coverage:
        coverage = np.zeros((height, width), np.float32)
    sgeo = kernel_geometry(envmap.layout, envmap.size, envmap.guard)
    dgeo = kernel_geometry(to, size, guard_px)
    log.debug(
        "resample %s -> %s N=%d S=%s filter=%s",
        envmap.layout.name,
        to.name,
        size,
        n_samples or "auto",
        filter,
    )
    src = np.ascontiguousarray(src)
    # A magnifying conversion integrates the area filter's linear reconstruction (no texel
    # blocks); next to a hole's or a partial view's texels (their V below 1) it keeps the box.
    linear = filter == "area" and not same_grid and magnifies(envmap, to, size)
    valid_channel = envmap.channels.index(VALID_CHANNEL) if VALID_CHANNEL in envmap.channels else -1
    # The chain averages blocks of level 0 with the kernel's own per-pixel weight sums.
    weights = np.zeros((height, width), np.float32) if mips else None
    if not _level0_unused(envmap, to, size, guard_px, irradiance, needs_coverage, mips):
        # A same-grid copy overwrites the kernel's colour: no rip-map for it to read.
        if filter == "area" and (guard_px or fill):
            # A point-sampled ring takes the one sample count a point-sampled chain would: a
            # chain's ring around a whole-sphere layout, and a fisheye ring past the point
            # behind the view (a view's other rings are the area filter's own: one exact
            # piece a pixel).
            folded = ring_past_antipode(to, size, "fill" if fill else guard_px)
            point_ring = (mips and not to.partial) or folded
            ring_samples = auto_samples(envmap, to, size) if point_ring else 1
            _area_with_guard(src, sgeo, to, size, guard_px, fill, n_samples, ring_samples, rot,
                             out, None if direct_alpha else coverage, weights, direct_alpha,
                             linear, valid_channel)  # fmt: skip
        else:
            rip, rip_levels, rip_row_count = source_rips(
                envmap, src, 1 if same_grid else n_samples, filter, to, size
            )
            kernels.resample_rows(
                src, rip, rip_levels, rip_row_count, sgeo, dgeo, 1.0, 1.0, n_samples or 0,
                FILTERS[filter], rot, fill, out, None if direct_alpha else coverage, weights,
                zeroed=True, coverage_channel=direct_alpha, linear=linear,
                valid_channel=valid_channel,
            )  # fmt: skip
            del rip
    if same_grid:
        # Same grid: every sample sits on a source pixel centre, where every filter returns that
        # pixel. Copy it exactly rather than through tap weights that round to 1e-16.
        _copy_covered(out, src, coverage)
    chain = [(out, coverage)]
    if mips:
        from .mips import build_chain, level_count

        count = level_count(to, size, guard_px, mips)
        chain = build_chain(
            envmap, to, size, guard_px, fill, n_samples, FILTERS[filter], rot, out, coverage,
            weights, count,
        )  # fmt: skip
    metadata = dict(envmap.metadata)
    if ggx or irradiance:
        from . import ibl

        if irradiance:
            chain = ibl.irradiance_levels(envmap, to, size, guard_px, fill, rot, chain)
        else:
            chain, rough = ibl.ggx_levels(envmap, to, size, guard_px, fill, rot, chain, roughness)
            metadata["envconv:roughness"] = " ".join(f"{r:.6g}" for r in rough)
    if alpha and not direct_alpha:
        if alpha_index is None:
            chain = [(np.concatenate([o, c[:, :, None]], axis=2), c) for o, c in chain]
        else:
            for o, c in chain:
                o[:, :, alpha_index] = c
    out = chain[0][0]
    if cout.remap is not None:
        out = apply_remap(to, out, guard_px, cout.remap, inverse=True)
    out, metadata = output_on_grid(out, cout, metadata)
    return EnvMap(
        out,
        to,
        guard=guard_px,
        channels=output_channels(envmap.channels, alpha),
        metadata=metadata,
        pixel_type=envmap.pixel_type,
        levels=[o for o, _ in chain] if mips else None,
    )


def _area_with_guard(src, sgeo, to, size, guard, fill, samples, ring_samples, rot, out,
                     coverage, weights, coverage_channel, linear=False, valid_channel=-1):  # fmt: skip
    """Level 0 of the area filter with a guard ring (``guard`` pixels) or ``fill``, into ``out``
    (as :func:`kernels.resample_rows` fills it).

    Every pixel with valid directions is the area filter's exact mean, made without the ring
    (a pixel across a disk's rim: the mean of its valid part). Around a whole-sphere layout a
    guard (or filled) pixel holds what a GPU reads across the cell's edge: a bilinear tap of
    that area-filtered map at the continued direction of the pixel's centre (``ring_samples``
    1; a mip chain's ring takes the sub-samples a point-sampled chain would, its block means
    needing one weight rule). So the ring costs the map no energy and adds none of its own.
    Around a partial view (``to.partial``) the ring is more of the view, where the map without
    it has no data: each ring pixel is the area filter's exact mean over its own footprint
    under the continued mapping (the grown image made by the area filter itself, on a
    geometry whose inverse map reaches over the whole image), its weight that solid angle.
    ``linear``, ``valid_channel``: as :func:`kernels.resample_rows` takes them.
    """
    inner_geometry = kernel_geometry(to, size, 0)
    width, height = to.image_size(size, 0)
    inner = np.zeros((height, width, src.shape[2]), np.float32)
    inner_coverage = np.zeros((height, width), np.float32)
    inner_weights = np.zeros((height, width), np.float32)
    no_rips = np.zeros((1, 1, src.shape[2]), np.float32)
    kernels.resample_rows(
        src, no_rips, 0, 0, sgeo, inner_geometry, 1.0, 1.0, samples or 1, kernels.AREA_FILTER,
        rot, False, inner, inner_coverage, inner_weights, zeroed=True, linear=linear,
        valid_channel=valid_channel,
    )  # fmt: skip
    if to.partial and ring_past_antipode(to, size, "fill" if fill else guard):
        # A fisheye ring that reaches the point behind the view: the continued map folds the
        # circle there onto that one direction and back, so a ring pixel has no footprint of
        # its own. The ring is point-sampled from the source at each pixel's continued
        # direction (as the bilinear kernel makes it); the view's pixels stay exact below.
        kernels.resample_rows(
            src, no_rips, 0, 0, sgeo, kernel_geometry(to, size, guard), 1.0, 1.0, ring_samples,
            kernels.FILTER_BILINEAR, rot, fill, out, coverage, weights, zeroed=True,
            coverage_channel=coverage_channel,
        )  # fmt: skip
        if weights is not None:
            weights *= 4.0 / (to.content_width(size) * size * ring_samples**2)
    elif to.partial:
        kernels.resample_rows(
            src, no_rips, 0, 0, sgeo, kernel_geometry(to, size, guard, output=True), 1.0, 1.0,
            samples or 1, kernels.AREA_FILTER, rot, fill, out, coverage, weights, zeroed=True,
            coverage_channel=coverage_channel, linear=linear, valid_channel=valid_channel,
        )  # fmt: skip
    else:
        kernels.resample_rows(
            inner, no_rips, 0, 0, inner_geometry, kernel_geometry(to, size, guard), 1.0, 1.0,
            ring_samples, kernels.FILTER_BILINEAR, np.eye(3), fill, out, coverage, weights,
            zeroed=True, coverage_channel=coverage_channel,
        )  # fmt: skip
        if weights is not None:
            # The point kernel's weight is S x S times a density per unit (a, b) area, the area
            # filter's a solid angle: the ring's are made solid angles too, for the block means.
            weights *= 4.0 / (to.content_width(size) * size * ring_samples**2)
    _paste_cells(to, size, guard, src.shape[2], inner, inner_coverage, inner_weights, out,
                 coverage, weights, coverage_channel)  # fmt: skip


def _paste_cells(to, size, guard, channels, inner, inner_coverage, inner_weights, out, coverage,
                 weights, coverage_channel):  # fmt: skip
    """Put the pixels of the ringless map ``inner`` that hold valid directions (with their
    coverage and weights) into the cells of the guarded ``out``."""
    inner_w, inner_h = to.cell_size(size, 0)
    cell_w, cell_h = to.cell_size(size, guard)
    for cell in to.cells:
        here = (slice(cell.row * inner_h, (cell.row + 1) * inner_h),
                slice(cell.col * inner_w, (cell.col + 1) * inner_w))  # fmt: skip
        there = (slice(cell.row * cell_h + guard, cell.row * cell_h + guard + inner_h),
                 slice(cell.col * cell_w + guard, cell.col * cell_w + guard + inner_w))  # fmt: skip
        valid = inner_coverage[here] > 0
        out[there][..., :channels][valid] = inner[here][valid]
        if coverage_channel:
            out[there][..., channels][valid] = inner_coverage[here][valid]
        elif coverage is not None:
            coverage[there][valid] = inner_coverage[here][valid]
        if weights is not None:
            weights[there][valid] = inner_weights[here][valid]


def _level0_unused(
    envmap: EnvMap, to: Layout, size: int, guard: int, irradiance: bool, needs_coverage: bool, mips
) -> bool:
    """True when nothing reads the resampled level 0: an irradiance map without alpha or chain
    whose convolution is summed from the source itself (binned, or resampled onto its cube)."""
    if not irradiance or needs_coverage or mips:
        return False
    from . import ibl

    return not ibl.irradiance_reads_level0(envmap, to, size, guard)


def memory_needed(envmap: EnvMap, to, size=None, guard=0, mips=None, alpha=False,
                  samples="auto", filter="area", out_convention=None) -> int | None:  # fmt: skip
    """Estimated peak bytes of :func:`convert` with these arguments and of writing its result
    (:func:`envconv.engine.memory.estimate_convert`); None for arguments :func:`convert` refuses."""
    from ..engine import memory

    try:
        layout = get_layout(to)
        chain, _ = _mip_filter(mips)
        if size is None:
            size = default_size(envmap, layout, resolve_convention(out_convention, layout),
                                mips=mips, guard=guard)  # fmt: skip
        guard_px = 0 if guard == "fill" else check_guard(guard)
    except (UsageError, LayoutError, ValueError, TypeError):
        return None
    if not isinstance(size, (int, np.integer)) or size < 1:
        return None
    rips = 0
    if check_samples(samples) is None and filter == "bilinear" and envmap.layout.name == "latlong" \
            and not envmap.guard:  # fmt: skip
        height, width, nch = envmap.pixels.shape
        levels = kernels.rip_level_count(width)
        rows = rip_rows(width, height, layout, int(size)) if levels else 0
        rows = min(height, 2 * min(rows, rip_row_cap(width, height)))
        rips = rows * (width - (width >> levels)) * (nch + int(envmap.valid is not None)) * 4
    # The area filter's per-thread tables, edge memos and band buffers (measured: up to about
    # 8 MB a thread for a 2048 x 1024 source).
    scratch = AREA_SCRATCH * kernels.get_threads() if filter in (None, "area") else 0
    if filter in (None, "area") and (guard == "fill" or guard_px):
        # _area_with_guard's map without the ring: its pixels, coverage and weights (around a
        # whole-sphere layout and around a view alike).
        width, height = layout.image_size(int(size), 0)
        scratch += width * height * (envmap.pixels.shape[2] + 2) * 4
    return memory.estimate_convert(envmap, layout, int(size), guard_px, chain, alpha, rips,
                                   scratch)  # fmt: skip


def _check_memory(envmap, to, size, guard, mips, alpha, samples, filter, out_convention):
    """Refuse, before allocating, a conversion whose estimated peak memory exceeds what is
    available (:mod:`envconv.engine.memory`); bad arguments are left for :func:`_resample` to name."""
    from ..engine import memory

    try:
        need = memory_needed(envmap, to, size, guard, mips, alpha, samples, filter, out_convention)
    except (UsageError, LayoutError):
        return
    if need is not None:
        name = get_layout(to).name
        memory.check(need, f"converting to {name} at size {size or 'default'}",
                     envmap.pixels.nbytes, "lower --size, or free memory")  # fmt: skip


def _copy_covered(out: np.ndarray, src: np.ndarray, coverage: np.ndarray) -> None:
    """Copy ``src`` into the first channels of ``out`` where ``coverage`` > 0, a block of rows
    at a time (the mask of a whole map would be one more plane in memory)."""
    nch = src.shape[2]
    rows = max(1, (1 << 20) // max(1, out.shape[1]))
    for y0 in range(0, out.shape[0], rows):
        block = slice(y0, y0 + rows)
        np.copyto(out[block, :, :nch], src[block], where=coverage[block, :, None] > 0)


def _mip_filter(mips):
    """(mips for the chain builder, True for GGX) of ``convert``'s ``mips``."""
    return check_mips(mips)


def _chain_request(levels, ggx: bool):
    """``mips`` as :func:`check_mips` takes it again, from its (levels, ggx)."""
    if levels is None:
        return None
    return ("ggx" if ggx else "box") + ("" if levels is True else f":{levels}")


def source_rips(
    envmap: EnvMap,
    src: np.ndarray,
    samples: int | None,
    filter: str,
    to: Layout | str | None = None,
    size: int | None = None,
):
    """(rip-map, levels, rows) for the kernel: a lat-long source's horizontal rip-map when
    adaptive sampling with the bilinear filter will read it, else an empty stand-in, 0 and 0.

    Only the rows next to each pole where output pixels of ``to`` at ``size`` can span enough
    texels along x to read a level are filled (:func:`rip_rows`); without ``to`` and ``size``,
    every row.
    """
    if (
        samples is None
        and filter == "bilinear"
        and envmap.layout.name == "latlong"
        and not envmap.guard
    ):
        height, width = src.shape[:2]
        rows = height if to is None or size is None else rip_rows(width, height, to, size)
        rows = min(rows, rip_row_cap(width, height))
        rip, levels = kernels.build_rips(src, rows)
        return rip, levels, rows
    return np.zeros((1, 1, src.shape[2]), np.float32), 0, 0


#: Largest share of the source's bytes the rip-map may hold (issue 15's memory bound, peak
#: ≤ 1.25 × (input + output), leaves less than a quarter of the input for it when the output
#: is small, and the kernel's buffers need some of that).
RIP_SHARE = 0.2


def rip_row_cap(width: int, height: int) -> int:
    """Most rows next to each pole a ``width`` × ``height`` lat-long's rip-map may fill: the
    filled rows hold at most RIP_SHARE of the source (about the rows within 18° of the
    poles, where a pixel spans the most texels). Nearer the horizon the kernel reads level 0
    with up to MAX_SAMPLES sub-samples per edge, as it does with the other filters."""
    levels = kernels.rip_level_count(width)
    if levels == 0:
        return 0
    packed = width - (width >> levels)
    return max(1, int(RIP_SHARE * height * width / (2 * packed)))


#: Output pitch is estimated from √Ω, which understates an anisotropic pixel's longer edge.
_ANISOTROPY = 2.0


def rip_rows(width: int, height: int, to: Layout | str, size: int) -> int:
    """Rows next to each pole of a ``width`` × ``height`` lat-long whose rip-map levels output
    pixels of layout ``to`` at ``size`` may read.

    A pixel reads level 1 or above where its two edges span at least 2 · RIP_MIN_SPAN texels
    along x (``RIP_MIN_SPAN`` in :mod:`envconv.resample.kernels`). An edge of θ radians spans at most
    W θ / (2π cos φ) texels along x at latitude φ, so that happens only where
    cos φ ≤ W · 2 θ_max / (2π · 2 kernels.RIP_MIN_SPAN). θ_max is the largest pixel pitch √Ω of the
    output over 4096 directions, times 2 for anisotropy; the rows are widened by θ_max (the
    pixel's own reach) and 3 rows. This is an estimate, not a bound: the kernel reads level 0
    wherever a pixel could reach an unfilled row, so a low estimate costs speed, never accuracy.
    Layouts with a singular rim (a mirror ball) fill every row.
    """
    count = 4096  # Fibonacci directions, evenly spread over the sphere
    k = np.arange(count) + 0.5
    polar = np.arccos(1.0 - 2.0 * k / count)
    azimuth = math.pi * (1.0 + 5.0**0.5) * k
    dirs = np.stack([np.sin(polar) * np.sin(azimuth), np.cos(polar),
                     np.sin(polar) * np.cos(azimuth)], -1)  # fmt: skip
    pitch = _ANISOTROPY * float(np.max(pixel_pitch(to, dirs))) / size
    cos_limit = width * 2.0 * pitch / (2.0 * math.pi * 2.0 * kernels.RIP_MIN_SPAN)
    if not np.isfinite(pitch) or cos_limit >= 1.0:
        return height
    from_pole = math.pi / 2 - math.acos(cos_limit) + pitch
    return min(height, int(math.ceil(from_pole / (math.pi / height))) + 3)
