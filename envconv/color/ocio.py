"""Colour management: the one module that owns OpenColorIO.

Pixels are numpy arrays of shape ``(H, W, C)``. Colour channels are the first three when
``C >= 3``; a 1- or 2-channel image is grey (plus alpha), and its channel 0 is the colour.
Alpha and extra channels are never colour-converted.

Colour-space names are OCIO names. :func:`resolve_colorspace` also accepts aliases, roles,
interop ids (``lin_rec709_scene``) and a few friendly spellings (``linear``, ``srgb``,
``rec709``, ``acescg``, ``aces``, ``raw``). PyOpenColorIO is imported lazily, so importing this
module is cheap. Every function is pure: nothing is read or written, nothing printed.

The working space is linear Rec.709 (OCIO's ``lin_rec709_scene``): all resampling happens in
scene-linear float32 there. :func:`to_working` converts a map into it (the input rule:
``input_colorspace``, else the file's ``oiio:ColorSpace``, else the format's default: linear
Rec.709 for float and half data, sRGB-encoded Rec.709 for 8- and 16-bit), keeping NaN and
Inf in their own channel. Storing a map (quantizing, dither) lives in :mod:`envconv.color.quantize`;
a file's output plan in :mod:`envconv.io.encode`.
"""

from __future__ import annotations

import dataclasses
import difflib
import logging
import os
import re
from functools import lru_cache
from typing import Any

import numpy as np

from ..envmap import EnvMap, map_levels
from ..errors import ColorError, UsageError
from ..limits import check_stops
from .quantize import as_image as _as_image
from .quantize import colour_slice as _colour

__all__ = [
    "WORKING_COLORSPACE",
    "config_for",
    "check_colorspace",
    "input_colorspace_of",
    "to_working",
    "working_pixels",
    "convert_keeping_nonfinite",
    "apply_exposure",
    "load_config",
    "builtin_config",
    "resolve_colorspace",
    "default_colorspace",
    "colorspace_from_metadata",
    "metadata_name",
    "convert_colorspace",
    "display_view",
    "VIEWS",
]

log = logging.getLogger(__name__)

DEFAULT_CONFIG = "ocio://default"

# Candidates tried in order (name, alias, role or interop id); the first in the config wins.
# Interop ids (OCIO >= 2.5 configs) first, then ACES 1.x names, then legacy (nuke-default).
_LIN_REC709 = ("lin_rec709_scene", "lin_rec709", "Utility - Linear - sRGB", "linear")
_SRGB_REC709 = ("srgb_rec709_scene", "srgb_tx", "Utility - sRGB - Texture", "sRGB")
_FRIENDLY: dict[str, tuple[str, ...]] = {
    "linear": _LIN_REC709,
    "lin": _LIN_REC709,
    "srgb": _SRGB_REC709,
    # Rec.709 video: OCIO/ACES configs decode it with the BT.1886 (gamma 2.4) EOTF.
    "rec709": ("rec709", "g24_rec709_scene", "rec709_display", "Utility - Rec.709 - Display"),
    "acescg": ("lin_ap1_scene", "ACEScg"),
    "aces": ("lin_ap0_scene", "ACES2065-1"),
    "raw": ("data", "Raw", "Utility - Raw"),
}
# Older OIIO wrote "GammaCorrected2.2" (and "Gamma2.2") to oiio:ColorSpace.
_GAMMA_METADATA = re.compile(r"gamma(?:corrected)?(18|22|24)")
_FLOAT_TYPES = frozenset("half float double float16 float32 float64".split())
_INT_TYPES = frozenset("uint8 uint16 int8 int16 uint int uint32 int32".split())
_LINEAR_FORMATS = frozenset("exr openexr sxr mxr hdr rgbe pic".split())


def _key(name: str) -> str:
    """Normalise a friendly spelling: lower case, no spaces, dashes, dots or underscores."""
    return re.sub(r"[\s._\-]", "", name.lower())


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _ocio():
    import PyOpenColorIO

    return PyOpenColorIO


def load_config(path: str | os.PathLike[str] | None = None) -> Any:
    """Load and validate an OpenColorIO config.

    Parameters
    ----------
    path : str or path-like, optional
        A ``config.ocio`` file or an ``ocio://`` URI. When None, ``$OCIO`` is used if set and
        non-empty, else OCIO's built-in default config ``ocio://default``.

    Returns
    -------
    PyOpenColorIO.Config

    Raises
    ------
    ColorError
        If the file is missing or the config cannot be parsed or fails validation. The
        one-line message names the path, where it came from and OCIO's reason.

    Examples
    --------
    >>> load_config().getName().startswith("cg-config")
    True
    """
    if path is not None:
        path, origin = os.fspath(path), "--ocio-config"
    elif os.environ.get("OCIO", "").strip():
        path, origin = os.environ["OCIO"].strip(), "$OCIO"
    else:
        path, origin = DEFAULT_CONFIG, "built-in default"
    if not path.startswith("ocio://") and not os.path.isfile(path):
        reason = "it is a directory" if os.path.isdir(path) else "no such file"
        raise ColorError(
            f"cannot load OCIO config {path!r} (from {origin}): {reason}; "
            "pass --ocio-config PATH to a config.ocio file or unset $OCIO"
        )
    ocio = _ocio()
    try:
        config = ocio.Config.CreateFromFile(path)
        config.validate()
    except (ocio.Exception, ocio.ExceptionMissingFile) as exc:
        raise ColorError(
            f"cannot load OCIO config {path!r} (from {origin}): {_one_line(exc)}"
        ) from exc
    log.debug("loaded OCIO config %r (%s) from %s", config.getName(), path, origin)
    return config


@lru_cache(maxsize=1)
def builtin_config() -> Any:
    """OCIO's built-in default config (``ocio://default``), loaded once and kept."""
    return load_config(DEFAULT_CONFIG)


def _all_colorspaces(config: Any) -> list[Any]:
    ocio = _ocio()
    return list(config.getColorSpaces(ocio.SEARCH_REFERENCE_SPACE_ALL, ocio.COLORSPACE_ALL))


def _lookup(config: Any, candidates: tuple[str, ...]) -> str | None:
    """First candidate found as a name, alias, role or interop id; return its canonical name."""
    interop = {}
    for cs in _all_colorspaces(config):
        get_id = getattr(cs, "getInteropID", None)  # OCIO >= 2.5
        if get_id is not None and get_id():
            interop.setdefault(get_id().lower(), cs.getName())
    for cand in candidates:
        cs = config.getColorSpace(cand)
        if cs is not None:
            return cs.getName()
        if cand.lower() in interop:
            return interop[cand.lower()]
    return None


def _close_matches(config: Any, name: str) -> list[str]:
    spellings: dict[str, str] = {}
    for cs in _all_colorspaces(config):
        for s in (cs.getName(), *cs.getAliases()):
            spellings.setdefault(s.lower(), s)
    for role in config.getRoleNames():
        spellings.setdefault(role.lower(), role)
    low = name.lower()
    found = difflib.get_close_matches(low, list(spellings), n=5, cutoff=0.6)
    found += [s for s in spellings if low in s and s not in found]
    return [spellings[s] for s in found[:5]]


def resolve_colorspace(config: Any, name: str) -> str:
    """Return the canonical config name of a colour space given by name, alias or role.

    Lookup is case-insensitive: exact names, aliases and roles (``scene_linear``) first, then
    interop ids (``lin_rec709_scene``), then friendly spellings (``linear``, ``srgb``,
    ``rec709``, ``acescg``, ``aces``, ``raw``; spaces, dots, dashes and underscores ignored).

    Raises
    ------
    ColorError
        If the name is unknown; the message lists up to five close matches.

    Examples
    --------
    >>> resolve_colorspace(load_config(), "linear")
    'Linear Rec.709 (sRGB)'
    """
    name = str(name).strip()
    if name:
        found = _lookup(config, (name,)) or _lookup(config, _FRIENDLY.get(_key(name), ()))
        if found is not None:
            return found
    where = f"OCIO config {config.getName() or '(unnamed)'!r}"
    close = _close_matches(config, name) if name else []
    if close:
        hint = "did you mean " + ", ".join(repr(c) for c in close) + "?"
    else:
        some = list(config.getColorSpaceNames())[:5]
        hint = "known spaces include " + ", ".join(repr(c) for c in some)
    raise ColorError(f"unknown colour space {name!r} in {where}; {hint}")


def default_colorspace(config: Any, file_format: str, pixel_type: Any) -> str:
    """Colour space assumed for a file that does not say (issue #4's rule).

    EXR and Radiance HDR, and any float/half data, are scene-linear with Rec.709 primaries;
    8- and 16-bit integer PNG/JPEG/TIFF (any integer data) are sRGB-encoded Rec.709.

    Parameters
    ----------
    config : PyOpenColorIO.Config
    file_format : str
        Format or extension: ``"openexr"``, ``"exr"``, ``".hdr"``, ``"png"``, ``"tiff"``...
    pixel_type : str or numpy dtype
        OIIO type name (``"half"``, ``"float"``, ``"uint8"``, ``"uint16"``) or a numpy dtype.

    Raises
    ------
    ColorError
        If the config has no matching space, or the pixel type is not recognised.

    Examples
    --------
    >>> default_colorspace(load_config(), "png", "uint8")
    'sRGB Encoded Rec.709 (sRGB)'
    """
    fmt = str(file_format).lower().lstrip(".")
    ptype = str(np.dtype(pixel_type) if isinstance(pixel_type, type) else pixel_type).lower()
    if fmt in _LINEAR_FORMATS or ptype in _FLOAT_TYPES:
        kind, candidates = "linear Rec.709", _LIN_REC709
    elif ptype in _INT_TYPES:
        kind, candidates = "sRGB-encoded Rec.709", _SRGB_REC709
    else:
        raise ColorError(
            f"cannot choose a default colour space for {fmt!r} with pixel type "
            f"{ptype!r}; pass --input-colorspace/--output-colorspace"
        )
    found = _lookup(config, candidates)
    if found is None:
        raise ColorError(
            f"OCIO config {config.getName()!r} has no {kind} colour space "
            f"(looked for {', '.join(candidates[:3])}); pass the colour space "
            "explicitly"
        )
    return found


def colorspace_from_metadata(value: str | None, config: Any = None) -> str | None:
    """Map an ``oiio:ColorSpace`` value (``"Linear"``, ``"sRGB"``, ``"lin_rec709"``...) to a name.

    Parameters
    ----------
    value : str or None
        The metadata value as read from the file.
    config : PyOpenColorIO.Config, optional
        Config to resolve against; the built-in default config when None.

    Returns
    -------
    str or None
        The canonical name in ``config``, or None if the value is empty or unknown (the caller
        then falls back to :func:`default_colorspace`).

    Examples
    --------
    >>> colorspace_from_metadata("srgb_rec709_scene")
    'sRGB Encoded Rec.709 (sRGB)'
    """
    if not value or not str(value).strip():
        return None
    config = builtin_config() if config is None else config
    try:
        return resolve_colorspace(config, str(value))
    except ColorError:
        m = _GAMMA_METADATA.fullmatch(_key(str(value)))
        return _lookup(config, (f"g{m[1]}_rec709_scene",)) if m else None


def metadata_name(config: Any, name: str) -> str:
    """The spelling of a colour space to store in a file's ``oiio:ColorSpace``.

    Its interop id (``lin_rec709_scene``, ``srgb_rec709_scene``, ``lin_ap1_scene``...) when the
    config gives one, since OIIO and other configs know those; else the config's own name.

    Examples
    --------
    >>> metadata_name(load_config(), "acescg")
    'lin_ap1_scene'
    """
    found = resolve_colorspace(config, name)
    get_id = getattr(config.getColorSpace(found), "getInteropID", None)  # OCIO >= 2.5
    interop = get_id() if get_id is not None else ""
    return interop or found


def convert_colorspace(pixels: np.ndarray, src: str, dst: str, config: Any) -> np.ndarray:
    """Convert the colour channels of an image from ``src`` to ``dst`` with OCIO's CPU path.

    Grey images (C = 1 or 2) are converted as (v, v, v) and the mean of the result is kept.
    Alpha and extra channels are copied unchanged; colour is not unpremultiplied.

    Parameters
    ----------
    pixels : ndarray, shape (H, W, C)
    src, dst : str
        Colour-space names, aliases or roles (see :func:`resolve_colorspace`).
    config : PyOpenColorIO.Config

    Returns
    -------
    ndarray of float32, shape (H, W, C)
        A new array; or the input itself (as float32) when ``src`` and ``dst`` resolve to the
        same space or the transform is a no-op.

    Examples
    --------
    >>> px = np.full((1, 1, 3), 0.5, np.float32)
    >>> round(float(convert_colorspace(px, "srgb", "linear", load_config())[0, 0, 1]), 4)
    0.214
    """
    arr = _as_image(pixels)
    src_name, dst_name = resolve_colorspace(config, src), resolve_colorspace(config, dst)
    if src_name == dst_name:
        return arr
    ocio = _ocio()
    try:
        proc = config.getProcessor(src_name, dst_name)
        if proc.isNoOp():
            return arr
        # Lossless optimisation: the default one's fast pow maps 1.0 to 1.00002 (sRGB decode).
        cpu = proc.getOptimizedCPUProcessor(ocio.OPTIMIZATION_LOSSLESS)
        sl = _colour(arr.shape[2])
        rgb = np.array(arr[..., sl], dtype=np.float32, order="C", copy=True)
        if rgb.shape[2] == 1:
            rgb = np.ascontiguousarray(np.repeat(rgb, 3, axis=2))
        cpu.applyRGB(rgb)  # in place
    except ocio.Exception as exc:
        raise ColorError(f"cannot convert {src_name!r} to {dst_name!r}: {_one_line(exc)}") from exc
    out = arr.copy()
    out[..., sl] = rgb if arr.shape[2] >= 3 else rgb.mean(axis=2, keepdims=True)
    return out


#: Preview views by friendly name: ``"tone"`` is the config's default view of its default
#: display (ACES 2.0 SDR 100 nits in the built-in config), ``"srgb"`` its un-tone-mapped view.
VIEWS = ("tone", "srgb")


def display_view(rgb: np.ndarray, view: str = "tone", config: Any = None) -> np.ndarray:
    """Scene-linear Rec.709 RGB to display code values through an OCIO display/view transform.

    Parameters
    ----------
    rgb : ndarray, shape (..., 3)
        Scene-linear Rec.709 (``lin_rec709``) values; exposure already applied.
    view : {"tone", "srgb"} or str
        ``"tone"``: the config's default view of its default display (in the built-in config,
        ``sRGB - Display`` / ``ACES 2.0 - SDR 100 nits (Rec.709)``); ``"srgb"``: the
        ``Un-tone-mapped`` view of that display; any other string is a view name of it.
    config : PyOpenColorIO.Config, optional
        Default: OCIO's built-in config (not ``$OCIO``, so previews look the same everywhere).

    Returns
    -------
    ndarray of float32, shape (..., 3)
        Display-encoded values, nominally in [0, 1] (not clipped).
    """
    config = builtin_config() if config is None else config
    ocio = _ocio()
    display = config.getDefaultDisplay()
    name = {"tone": config.getDefaultView(display), "srgb": "Un-tone-mapped"}.get(view, view)
    if name not in list(config.getViews(display)):
        raise ColorError(f"no view {view!r} for display {display!r}; try one of: tone, srgb, "
                         + ", ".join(config.getViews(display)))  # fmt: skip
    src = resolve_colorspace(config, "linear")
    try:
        proc = config.getProcessor(src, display, name, ocio.TRANSFORM_DIR_FORWARD)
        cpu = proc.getOptimizedCPUProcessor(ocio.OPTIMIZATION_LOSSLESS)
        out = np.array(np.reshape(rgb, (-1, 1, 3)), dtype=np.float32, order="C", copy=True)
        cpu.applyRGB(out)
    except ocio.Exception as exc:
        raise ColorError(f"cannot apply view {name!r}: {_one_line(exc)}") from exc
    return out.reshape(np.shape(rgb))


#: The working space, as a friendly name resolved in the config (linear Rec.709).
WORKING_COLORSPACE = "linear"


@lru_cache(maxsize=8)
def _load(path: str | None, env: str | None) -> Any:
    if path is None and not (env or "").strip():
        return builtin_config()
    return load_config(path)


def config_for(ocio_config: str | os.PathLike | None) -> Any:
    """The config from ``ocio_config``, else ``$OCIO``, else ``ocio://default`` (cached)."""
    path = None if ocio_config is None else os.fspath(ocio_config)
    return _load(path, os.environ.get("OCIO"))


def check_colorspace(name: str, ocio_config: str | os.PathLike | None = None) -> str:
    """The canonical name of a colour space the user named (an option, a graph file's key),
    or UsageError with the close names: an unknown name is bad usage (exit 2), found before
    any work. A config that cannot be loaded stays a ColorError."""
    config = config_for(ocio_config)
    try:
        return resolve_colorspace(config, name)
    except ColorError as exc:
        raise UsageError(str(exc)) from None


def input_colorspace_of(
    metadata: dict, pixel_type: str, input_colorspace: str | None = None, ocio_config=None
) -> str:
    """Canonical name of the colour space a map's pixels are in (the input rule).

    ``input_colorspace`` when given, else the ``oiio:ColorSpace`` in ``metadata`` when the
    config knows it, else linear Rec.709 for float/half and sRGB for integer ``pixel_type``.
    """
    config = config_for(ocio_config)
    if input_colorspace:
        return resolve_colorspace(config, input_colorspace)
    found = colorspace_from_metadata(metadata.get("oiio:ColorSpace"), config)
    return found or default_colorspace(config, "", pixel_type or "float")


def convert_keeping_nonfinite(pixels: np.ndarray, src: str, dst: str, config: Any) -> np.ndarray:
    """Colour conversion that keeps NaN/Inf in their own channel (a matrix would spread them)."""
    if src == dst:  # nothing to convert: no NaN scan over the whole image
        return convert_colorspace(pixels, src, dst, config)
    sl = _colour(pixels.shape[2])
    bad = ~np.isfinite(pixels[..., sl])
    if not bad.any():
        return convert_colorspace(pixels, src, dst, config)
    clean = pixels.copy()
    clean[..., sl] = np.where(bad, np.float32(0.0), pixels[..., sl])
    out = convert_colorspace(clean, src, dst, config)
    out[..., sl] = np.where(bad, pixels[..., sl], out[..., sl])
    return out


def working_pixels(
    pixels: np.ndarray,
    metadata: dict,
    pixel_type: str,
    input_colorspace: str | None = None,
    ocio_config: str | os.PathLike | None = None,
) -> np.ndarray:
    """``pixels`` of a file with this ``metadata`` and ``pixel_type``, converted to the
    working space as :func:`to_working` converts a map's (for images that are not maps)."""
    config = config_for(ocio_config)
    src = input_colorspace_of(metadata, pixel_type, input_colorspace, ocio_config)
    return convert_keeping_nonfinite(
        pixels, src, resolve_colorspace(config, WORKING_COLORSPACE), config
    )


def to_working(
    envmap: EnvMap,
    input_colorspace: str | None = None,
    ocio_config: str | os.PathLike | None = None,
) -> EnvMap:
    """Convert a map's colour to the working space (linear Rec.709); no-op if it is there.

    The map's colour space is ``input_colorspace``, else its ``oiio:ColorSpace``, else the
    format default for its ``pixel_type`` (see :func:`input_colorspace_of`).
    :func:`envconv.io.read` calls this, so maps it returns are already in the working space
    (give it ``input_colorspace`` to override the file's). ``oiio:ColorSpace`` is set to the
    working space; chromaticities are dropped when the colour changed (they described the
    input). NaN and Inf stay where they were.
    """
    config = config_for(ocio_config)
    src = input_colorspace_of(envmap.metadata, envmap.pixel_type, input_colorspace, ocio_config)
    dst = resolve_colorspace(config, WORKING_COLORSPACE)
    metadata = dict(envmap.metadata)
    metadata.pop("colorInteropID", None)  # OIIO's EXR reader's copy of the colour space
    metadata["oiio:ColorSpace"] = metadata_name(config, dst)
    if src == dst:
        return dataclasses.replace(envmap, metadata=metadata)
    log.info("input colour space %s -> working space %s", src, dst)
    metadata.pop("chromaticities", None)
    return map_levels(
        envmap, lambda px: convert_keeping_nonfinite(px, src, dst, config), metadata=metadata
    )


def apply_exposure(pixels: np.ndarray, stops: float) -> np.ndarray:
    """Multiply the colour channels by ``2 ** stops`` (alpha and extras untouched).

    Returns a new float32 array, or the input itself when ``stops == 0``.

    Examples
    --------
    >>> apply_exposure(np.ones((1, 1, 4), np.float32), -1).ravel().tolist()
    [0.5, 0.5, 0.5, 1.0]
    """
    stops = check_stops(stops)
    arr = _as_image(pixels)
    if stops == 0.0:
        return arr
    out = arr.copy()
    out[..., _colour(arr.shape[2])] *= np.float32(2.0**stops)
    return out
