"""Tone-mapped previews and the contact sheet: look at a map before it ships.

**Preview transform** (:func:`tone_map`), for any 8-bit picture of an HDR map:

1. *Automatic exposure*: the log-average (geometric mean) Rec.709 luminance of the map,
   ``L̄ = exp(Σ w·ln max(L, 2⁻²⁰) / Σ w)`` with w the pixel's solid angle when given (else 1),
   is scaled to mid-grey 0.18: the gain is ``0.18 / L̄`` (:func:`auto_exposure` returns it in
   stops). Non-finite pixels and pixels outside the valid region (alpha 0) are skipped.
   ``exposure`` (stops) is added on top; ``auto=False`` uses ``exposure`` alone.
2. *Tone curve*: an OpenColorIO display/view transform of OCIO's built-in config
   (:func:`envconv.color.ocio.display_view`): ``"tone"`` is ACES 2.0 SDR 100 nits (Rec.709) on an
   sRGB display, ``"srgb"`` the un-tone-mapped sRGB view (values above 1 clip).
3. *Alpha* (a channel named A): the picture is composited over a grey checkerboard of 8-pixel
   squares (display values 0.4 and 0.6), in display space.
4. Rounded to uint8.

**Contact sheet** (:func:`contact_sheet`): the map in its own layout; six 90° perspective
views along the world axes of envconv's frame (right-handed, +Y up: OpenEXR/USD) or, with
``convention``, of that tool's frame (Blender's "+Z" is envconv's +Y), each an
unmirrored view from the centre, taken from the cube faces of ``envconv.convert``; a mirror
ball (layout ``sphere``: an orthographic camera looking along −Z at a mirror ball); a diffuse
ball (the same camera looking at a white Lambertian ball, lit by the map's irradiance); a line
of statistics. Everything but the statistics is computed from a working lat-long of height
``WORK_HEIGHT`` (the map is downsized first), so a 16K map takes seconds.
"""

from __future__ import annotations

import logging

import numpy as np

from ..envmap import EnvMap, alpha_channel
from ..layouts.geometry import dir_to_uv, pixel_directions, pixel_solid_angles
from .font import draw_text, text_width

__all__ = ["MID_GREY", "WORK_HEIGHT", "VIEW_FACES", "auto_exposure", "tone_map", "checkerboard",
           "working_map", "view_axes", "perspective_views", "mirror_ball", "diffuse_ball", "map_stats",
           "contact_sheet", "preview_picture"]  # fmt: skip

log = logging.getLogger(__name__)

MID_GREY = 0.18
#: Height of the working lat-long every view of the contact sheet is made from.
WORK_HEIGHT = 512
#: World axis → index of the cube-faces cell (px nx py ny pz nz) that is the unmirrored view
#: along it. envconv's cube faces follow the GL table in the left-handed frame (−x, y, z)
#: (docs/conventions.md), so the "px" cell looks along world −X.
VIEW_FACES = {"+X": 1, "-X": 0, "+Y": 2, "-Y": 3, "+Z": 4, "-Z": 5}
_LUMA = np.array([0.2126, 0.7152, 0.0722])
_FLOOR = 2.0**-20


def _rgb_alpha(pixels: np.ndarray, channels) -> tuple[np.ndarray, np.ndarray | None]:
    at = alpha_channel(channels) if channels else None
    alpha = pixels[..., at] if at is not None else None
    colour = [k for k in range(pixels.shape[2]) if k != at][:3]
    rgb = pixels[..., colour]
    if rgb.shape[-1] < 3:
        rgb = np.repeat(rgb[..., :1], 3, axis=-1)
    return rgb.astype(np.float32), alpha


def auto_exposure(rgb: np.ndarray, weights: np.ndarray | None = None) -> float:
    """Exposure in stops that takes the log-average luminance of ``rgb`` (..., 3) to 0.18.

    ``weights`` (same shape without the last axis) weight each pixel, e.g. its solid angle
    times its alpha; non-finite pixels are skipped. Returns 0 when nothing is left.
    """
    lum = np.asarray(rgb, np.float64) @ _LUMA
    w = np.ones(lum.shape) if weights is None else np.asarray(weights, np.float64)
    keep = np.isfinite(lum) & (w > 0)
    if not keep.any():
        return 0.0
    log_mean = np.sum(w[keep] * np.log(np.maximum(lum[keep], _FLOOR))) / np.sum(w[keep])
    return float(np.log2(MID_GREY) - log_mean / np.log(2.0))


def checkerboard(height: int, width: int, cell: int = 8) -> np.ndarray:
    """(height, width) display values 0.4 and 0.6 in ``cell``-pixel squares."""
    yy, xx = np.mgrid[0:height, 0:width]
    return np.where(((yy // cell) + (xx // cell)) % 2 == 0, 0.6, 0.4).astype(np.float32)


def tone_map(pixels, channels=None, exposure: float = 0.0, auto: bool = True,
             view: str = "tone", weights=None) -> np.ndarray:  # fmt: skip
    """(H, W, 3) uint8 display picture of scene-linear ``pixels`` (H, W, C).

    See the module docstring for the rule. ``channels`` names the channels (an "A" is alpha;
    default: the first three are colour). ``weights`` are passed to :func:`auto_exposure`.
    """
    from ..color.ocio import display_view

    pixels = np.asarray(pixels, np.float32)
    rgb, alpha = _rgb_alpha(pixels, channels)
    if alpha is not None:
        weights = alpha if weights is None else weights * alpha
    stops = exposure + (auto_exposure(rgb, weights) if auto else 0.0)
    scaled = np.nan_to_num(rgb * np.float32(2.0**stops), nan=0.0, posinf=65504.0, neginf=0.0)
    shown = np.clip(display_view(np.maximum(scaled, 0.0), view), 0.0, 1.0)
    if alpha is not None:
        a = np.clip(np.nan_to_num(alpha), 0.0, 1.0)[..., None]
        shown = a * shown + (1.0 - a) * checkerboard(*shown.shape[:2])[..., None]
    return np.round(shown * 255.0).astype(np.uint8)


def working_map(envmap: EnvMap, in_convention=None, height: int = WORK_HEIGHT) -> EnvMap:
    """The map as a lat-long of ``height`` (default :data:`WORK_HEIGHT`; less for a smaller
    map), in envconv's frame.

    A lat-long more than four times that high is first box-averaged by an integer factor to
    at least twice that height (a k × k block of a lat-long is a lat-long pixel, its mean the
    area mean up to the cos(latitude) weighting within k rows), which a 16K map reaches in a
    fraction of the time the resampler's pyramid of the full map takes.
    """
    from ..resample.convert import convert
    from ..resample.options import default_size

    size = min(height, default_size(envmap, "latlong"))
    rows = envmap.pixels.shape[0]
    plain = envmap.layout.name == "latlong" and envmap.guard == 0 and envmap.valid is None
    if plain and rows > 4 * size:
        step = rows // (2 * size)
        if envmap.pixels.shape[1] == 2 * rows and rows % step == 0:
            envmap = EnvMap(_box_average(envmap.pixels, step), envmap.layout,
                            channels=envmap.channels, metadata=envmap.metadata)  # fmt: skip
    return convert(envmap, "latlong", size=size, in_convention=in_convention)


def view_axes(convention=None) -> dict[str, str]:
    """Axis of a tool's world frame ("+X" … "-Z") → the axis of envconv's frame it is.

    ``convention`` is a preset name or an AXES frame (:func:`envconv.layouts.conventions.world_frame`);
    e.g. Blender (Z-up right-handed) gives {"+Z": "+Y", "+Y": "-Z", …}.
    """
    from ..layouts.conventions import world_frame

    frame, _ = world_frame(convention)
    out = {}
    for axis in VIEW_FACES:
        e = np.zeros(3)
        e["XYZ".index(axis[1])] = 1.0 if axis[0] == "+" else -1.0
        d = frame @ e
        k = int(np.argmax(np.abs(d)))
        out[axis] = ("+" if d[k] > 0 else "-") + "XYZ"[k]
    return out


def perspective_views(work: EnvMap, size: int = 256, convention=None) -> dict[str, np.ndarray]:
    """Six 90° perspective views (size, size, C) from the centre, keyed "+X" … "-Z".

    Each is the unmirrored picture a camera at the centre sees looking along the world axis
    (in envconv's frame: up +Y for the four horizon views, −Z for "+Y", +Z for "-Y"). With a
    ``convention`` the keys are the axes of that tool's world frame (:func:`view_axes`): the
    view keyed "+Z" for Blender is envconv's "+Y" view.
    """
    from ..resample.convert import convert

    cube = convert(work, "cube-faces", size=size).pixels
    ours = {axis: cube[:, size * k : size * (k + 1)] for axis, k in VIEW_FACES.items()}
    return {axis: ours[envconv_axis] for axis, envconv_axis in view_axes(convention).items()}


def mirror_ball(work: EnvMap, size: int = 256) -> EnvMap:
    """A mirror ball (layout ``sphere``) seen by an orthographic camera looking along −Z."""
    from ..resample.convert import convert

    return convert(work, "sphere", size=size, alpha=True)


def diffuse_ball(work: EnvMap, size: int = 256) -> np.ndarray:
    """(size, size, 4) a white Lambertian ball lit by the map, camera looking along −Z.

    A pixel of normal n shows the irradiance E(n)/π (envconv's ``irradiance=True``, a 32-high
    lat-long read bilinearly); alpha is 1 on the disk, 0 outside.
    """
    from ..layouts.geometry import kernel_geometry
    from ..resample import kernels
    from ..resample.convert import convert

    irr = convert(work, "latlong", size=32, irradiance=True)
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    x, y = np.meshgrid(c, -c)
    r2 = x * x + y * y
    normals = np.stack([x, y, np.sqrt(np.maximum(1.0 - r2, 0.0))], axis=-1)
    u, v = dir_to_uv("latlong", normals, 32)
    rgb, _ = _rgb_alpha(irr.pixels, irr.channels)
    h, w = rgb.shape[:2]
    points = np.stack([u * w, v * h], axis=-1).reshape(-1, 2)  # image points, pixel units
    # The core's seam-aware bilinear tap (wraps in u, continues over the poles).
    shade = kernels.filtered_reads(rgb, kernel_geometry("latlong", 32), [0], points,
                                   kernels.FILTER_BILINEAR)  # fmt: skip
    out = np.zeros((size, size, 4), np.float32)
    out[..., :3] = shade.reshape(size, size, 3)
    out[..., 3] = r2 <= 1.0
    return out


def _range_and_nans(envmap: EnvMap) -> tuple[float, float, int]:
    """(min, max) of the finite colour values and the NaN count of every channel, read in
    bands of rows so a 16K map needs no full-size temporary. A band whose min and max are
    finite has neither NaN nor Inf (both propagate or are extreme), so it takes two passes."""
    names = [c.upper() for c in envmap.channels] or ["R", "G", "B"]
    cols = [k for k, c in enumerate(names) if c != "A"][:3] or [0]
    every = cols == list(range(envmap.pixels.shape[2]))
    lo, hi, nans = np.inf, -np.inf, 0
    for start in range(0, envmap.pixels.shape[0], 256):
        band = envmap.pixels[start : start + 256]
        rgb = band if every else band[..., cols]
        b_lo, b_hi = float(rgb.min()), float(rgb.max())
        if every and np.isfinite(b_lo) and np.isfinite(b_hi):
            lo, hi = min(lo, b_lo), max(hi, b_hi)
            continue
        nans += int(np.count_nonzero(np.isnan(band)))
        finite = np.isfinite(rgb)
        values = rgb if finite.all() else rgb[finite]
        if values.size:
            lo, hi = min(lo, float(values.min())), max(hi, float(values.max()))
    return (lo, hi, nans) if lo <= hi else (float("nan"), float("nan"), nans)


def map_stats(envmap: EnvMap, work: EnvMap) -> dict:
    """Layout, size, range (finite colour values) and NaN count (all channels) of ``envmap``
    itself; mean radiance (per steradian, solid-angle weighted) and the brightest direction
    (the brightest pixel's centre) from the working lat-long ``work``."""
    from .info import mean_radiance

    lo, hi, nans = _range_and_nans(envmap)
    wrgb, _ = _rgb_alpha(work.pixels, work.channels)
    lum = np.nan_to_num(wrgb.astype(np.float64) @ _LUMA, nan=-1.0)
    row, col = np.unravel_index(np.argmax(lum), lum.shape)
    dirs = pixel_directions("latlong", work.size)[0]
    return {
        "layout": envmap.layout.name,
        "width": envmap.pixels.shape[1],
        "height": envmap.pixels.shape[0],
        "min": lo,
        "max": hi,
        "nan": nans,
        "mean": mean_radiance(EnvMap(wrgb, work.layout))[:3],
        "brightest": tuple(float(v) for v in dirs[row, col]),
    }


def _stats_line(s: dict) -> str:
    d = s["brightest"]
    mean = ",".join(f"{v:.3g}" for v in s["mean"])
    return (f"{s['layout']} {s['width']}x{s['height']}  range [{s['min']:.3g}, {s['max']:.3g}]"
            f"  NaN {s['nan']}  mean ({mean})  brightest ({d[0]:+.2f},{d[1]:+.2f},{d[2]:+.2f})")  # fmt: skip


def _box_average(pixels: np.ndarray, step: int) -> np.ndarray:
    """(H // step, W // step, C) means of step × step blocks (trailing rows and columns
    dropped), in bands of rows so a 16K map needs no full-size temporary: rows are summed
    first, adding whole contiguous rows, then the columns of the step times smaller result."""
    h, w = (np.array(pixels.shape[:2]) // step) * step
    c = pixels.shape[2]
    band = step * max(1, 256 // step)
    out = []
    for start in range(0, h, band):
        px = pixels[start : min(start + band, h), :w]
        rows = px.shape[0] // step
        acc = px.reshape(rows, step, w * c).sum(axis=1, dtype=np.float64)
        cols = acc.reshape(rows, w // step, step, c)
        total = cols[:, :, 0].copy()
        for k in range(1, step):  # faster than a reduction over the short middle axis
            total += cols[:, :, k]
        out.append((total / (step * step)).astype(np.float32))
    return np.concatenate(out, axis=0)


def _thumbnail(envmap: EnvMap, max_width: int) -> np.ndarray:
    """The map's own pixels, box-averaged by an integer factor to at most ``max_width``."""
    return _box_average(envmap.pixels, max(1, -(-envmap.pixels.shape[1] // max_width)))


def contact_sheet(envmap: EnvMap, exposure: float = 0.0, view: str = "tone",
                  in_convention=None, cell: int = 192, convention=None) -> np.ndarray:  # fmt: skip
    """(H, W, 3) uint8 labelled contact sheet of ``envmap`` (see the module docstring).

    One exposure (automatic, from the working lat-long's solid-angle-weighted log-average,
    plus ``exposure``) is used for every panel, so panels compare. ``convention`` (a preset
    name or an AXES frame) shows and labels the six views in that tool's world axes.
    """
    from ..layouts.conventions import world_frame

    work = working_map(envmap, in_convention)
    wrgb, _ = _rgb_alpha(work.pixels, work.channels)
    stops = exposure + auto_exposure(wrgb, pixel_solid_angles("latlong", work.size))
    pad, label = 8, 18
    width = 6 * cell + 7 * pad
    thumb = _thumbnail(envmap, width - 2 * pad)
    thumb_h = thumb.shape[0]
    views = perspective_views(work, cell, convention)
    frame_name = world_frame(convention)[1].upper()
    balls = [("MIRROR BALL", mirror_ball(work, cell).pixels, ("R", "G", "B", "A")),
             ("DIFFUSE BALL", diffuse_ball(work, cell), ("R", "G", "B", "A"))]  # fmt: skip
    height = pad + label + thumb_h + 2 * (pad + label + cell) + pad + label + pad
    sheet = np.full((height, width, 3), 24, np.uint8)
    shade = (230, 230, 230)

    def place(img, names, x, y, title):
        draw_text(sheet, title, x, y, shade, 2)
        sheet[y + label : y + label + img.shape[0], x : x + img.shape[1]] = tone_map(
            img, names, stops, auto=False, view=view
        )

    own_names = envmap.channels or None
    place(thumb, own_names, pad, pad, f"{envmap.layout.name.upper()} (AS STORED)"
          f"   VIEWS IN {frame_name} AXES")  # fmt: skip
    y = pad + label + thumb_h + pad
    for k, (axis, img) in enumerate(views.items()):
        place(img, work.channels, pad + k * (cell + pad), y, axis)
    y += label + cell + pad
    for k, (title, img, names) in enumerate(balls):
        place(img, names, pad + k * (cell + pad), y, title)
    note = f"EXPOSURE {stops:+.2f} STOPS (AUTO {stops - exposure:+.2f})  VIEW {view}"
    draw_text(sheet, note.upper(), pad + 2 * (cell + pad), y + label, shade, 2)
    y += label + cell + pad
    line = _stats_line(map_stats(envmap, work)).upper()
    scale = 2 if text_width(line, 2) <= width - 2 * pad else 1
    draw_text(sheet, line, pad, y, shade, scale)
    return sheet


def preview_picture(envmap: EnvMap, exposure: float = 0.0, view: str = "tone") -> np.ndarray:
    """(H, W, 3) uint8 tone-mapped picture of ``envmap`` in its own layout, full size.

    Automatic exposure weights each pixel by its solid angle (0 outside the valid region).
    """
    weights = pixel_solid_angles(envmap.layout, envmap.size, envmap.guard, samples=1)
    return tone_map(envmap.pixels, envmap.channels, exposure, True, view, weights)
