"""``envconv view``: one self-contained HTML page to look around inside an environment map.

The page (template ``viewer_page.html`` beside this module) is WebGL2 and needs no network:
the map, its irradiance and the display transforms are embedded in it as JSON.

- **Map**: the input resampled to envconv's lat-long (envconv's frame, docs/geometry.md), at
  most ``CAP_HEIGHT`` × 2·``CAP_HEIGHT`` (2048 × 1024), as Radiance RGBE bytes in base64
  (negative and non-finite values become 0); :func:`envconv.views.preview.working_map` makes it, so a
  lat-long over four times the cap is box-averaged by an integer factor first. **Irradiance**: a 32 × 64 lat-long of E/π
  (``irradiance=True``), lighting the diffuse ball. **GGX levels**: the split-sum GGX
  prefilter of :mod:`envconv.resample.ibl` at the perceptual roughness of ``GGX_LEVELS`` (α = r²), each
  a small lat-long (``mips="ggx:2"`` level 1: 128 × 64 for r = 0.25, 64 × 32 above, about
  60 KB of base64 in all). The rough ball shows, at its reflection vector, these levels
  interpolated linearly in r (r = 0 is the map itself), as engines blend mip levels.
- **Display**: the exposure slider starts at the automatic exposure of
  :func:`envconv.views.preview.auto_exposure` (solid-angle-weighted log-average luminance to 0.18).
  The tone curve is OCIO's built-in config's default view (ACES 2.0 SDR) baked into a
  33³ 3D LUT, and the un-tone-mapped sRGB view into a 1024-entry 1D LUT, both over the
  shaper ``s = (log2 x − SHAPER[0]) / (SHAPER[1] − SHAPER[0])`` (half floats).
- **Conventions**: each preset's lat-long matrix M (:mod:`envconv.layouts.conventions`): with a
  preset selected, the page shows the file as that tool would, i.e. at world direction w the
  pixel of envconv direction Mᵀw.
- **URL fragment** (for links and tests): ``#view=+X`` (any of ±X ±Y ±Z; up +Y, or −Z for
  +Y and +Z for −Y), ``conv=NAME``, ``rough=`` (the rough ball's roughness, 0 to 1), ``yaw=``, ``pitch=``, ``fov=`` (degrees, vertical),
  ``exposure=`` (stops, absolute), ``tone=0`` (un-tone-mapped sRGB), ``spheres=0``,
  ``grid=1``, ``labels=0``, ``ui=0`` (hide the control panel). The document title ends in "(ready)" once the first frame is drawn.
"""

from __future__ import annotations

import base64
import html
import json
import logging
from importlib import resources

import numpy as np

from ..envmap import EnvMap

__all__ = [
    "CAP_HEIGHT",
    "SHAPER",
    "GGX_LEVELS",
    "ggx_page_levels",
    "rgbe_encode",
    "page_presets",
    "build_page",
]

log = logging.getLogger(__name__)

#: Height cap of the embedded lat-long (its width is twice this).
CAP_HEIGHT = 1024
#: log2 range of the display LUTs' input: 2⁻¹² to 2⁸ (0.00024 to 256 after exposure).
SHAPER = (-12.0, 8.0)
#: (perceptual roughness, level-0 height of the ggx:2 chain whose level 1 is embedded).
GGX_LEVELS = ((0.25, 128), (0.5, 64), (0.75, 64), (1.0, 64))


def rgbe_encode(rgb: np.ndarray) -> np.ndarray:
    """(H, W, 3) float → (H, W, 4) uint8 Radiance RGBE (value = (byte + 0.5)·2^(E − 136)).

    Negative and non-finite values are stored as 0.
    """
    rgb = np.nan_to_num(np.asarray(rgb, np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    rgb = np.maximum(rgb, 0.0)
    peak = rgb.max(axis=-1)
    mant, exp = np.frexp(peak)
    out = np.zeros(rgb.shape[:-1] + (4,), np.uint8)
    keep = peak > 1e-32
    scale = np.where(keep, mant * 256.0 / np.where(keep, peak, 1.0), 0.0)
    out[..., :3] = np.clip(np.floor(rgb * scale[..., None]), 0, 255).astype(np.uint8)
    out[..., 3] = np.where(keep, exp + 128, 0).astype(np.uint8)
    return out


def page_presets() -> dict[str, list[float]]:
    """Convention name → its lat-long M, column-major (as WebGL's uniformMatrix3fv takes)."""
    from ..layouts.conventions import PRESETS, resolve_convention

    out = {}
    for name in PRESETS:
        try:
            conv = resolve_convention(name, "latlong")
        except Exception:  # noqa: BLE001 - presets that do not apply to lat-longs are left out
            continue
        out[name] = [float(v) for v in np.asarray(conv.matrix, float).T.ravel()]
    return out


def _luts() -> dict:
    from ..color.ocio import display_view

    lo, hi = SHAPER
    n3, n1 = 33, 1024
    g = np.exp2(lo + (hi - lo) * np.linspace(0.0, 1.0, n3))
    b, gg, r = np.meshgrid(g, g, g, indexing="ij")  # 3D texture: x = R fastest, z = B
    cube = np.stack([r, gg, b], axis=-1)
    tone = np.concatenate([display_view(cube, "tone"), np.ones(cube.shape[:-1] + (1,))], axis=-1)
    ramp = np.exp2(lo + (hi - lo) * np.linspace(0.0, 1.0, n1))
    line = display_view(np.repeat(ramp[:, None], 3, axis=1), "srgb")
    line = np.concatenate([line, np.ones((n1, 1))], axis=-1)

    def half(a):
        return base64.b64encode(np.clip(a, 0.0, 1.0).astype("<f2").tobytes()).decode()

    return {"lut3": {"size": n3, "data": half(tone)}, "lut1": {"size": n1, "data": half(line)}}


def _embedded(env: EnvMap) -> dict:
    rgb = env.pixels[..., :3]
    h, w = rgb.shape[:2]
    return {"width": w, "height": h, "rgbe": base64.b64encode(rgbe_encode(rgb).tobytes()).decode()}


def ggx_page_levels(work: EnvMap) -> list[EnvMap]:
    """The GGX-prefiltered lat-longs of ``work`` embedded for the rough ball, one per
    :data:`GGX_LEVELS` entry (level 1 of a ``mips="ggx:2"`` chain with that roughness),
    prefiltered from ``work`` resampled to at most 512 high (0.35° pixels, fine for lobes of
    r ≥ 0.25; half the time of a 1024-high source, and within 1% of it)."""
    from ..resample.convert import convert

    if work.pixels.shape[0] > 512:
        work = convert(work, "latlong", size=512)
    out = []
    for rough, height in GGX_LEVELS:
        chain = convert(work, "latlong", size=height, mips="ggx:2", roughness=[rough])
        out.append(EnvMap(chain.levels[1], "latlong"))
    return out


def build_page(envmap: EnvMap, title: str = "", in_convention=None, cap: int = CAP_HEIGHT) -> str:
    """The viewer page for ``envmap`` as one HTML string (see the module docstring).

    ``in_convention`` says how to read the map (as for ``envconv.convert``); ``cap`` is the
    height cap of the embedded lat-long.
    """
    from ..layouts.geometry import pixel_solid_angles
    from ..resample.convert import convert
    from .preview import auto_exposure, working_map

    work = working_map(envmap, in_convention, cap)
    irr = convert(work, "latlong", size=32, irradiance=True)
    stops = auto_exposure(work.pixels[..., :3], pixel_solid_angles("latlong", work.size))
    data = {
        "env": _embedded(work), "irr": _embedded(irr), "exposure": round(stops, 2),
        "ggx": {"rough": [r for r, _ in GGX_LEVELS],
                "levels": [_embedded(level) for level in ggx_page_levels(work)]},
        "shaper": list(SHAPER), "conventions": page_presets(),
        "info": f"{title}: {envmap.layout.name} {envmap.pixels.shape[1]}x{envmap.pixels.shape[0]}"
                f", shown as a {work.pixels.shape[1]}x{work.pixels.shape[0]} lat-long",
        **_luts(),
    }  # fmt: skip
    template = resources.files(__package__).joinpath("viewer_page.html").read_text("utf-8")
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    return template.replace("__TITLE__", html.escape(title)).replace("__DATA__", payload)
