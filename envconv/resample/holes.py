"""Resampling a map as its file held it: holes left by the data window, and parts.

:func:`envconv.resample.convert.convert` hands a map with holes or parts to :func:`convert_with_holes`,
so every entry point (``envconv.convert``, ``convert``, chains, graph files and batches)
resamples a map read from a file alike.

Holes
    A map read from a file whose data window leaves part of its display window empty has
    ``EnvMap.valid`` (1 where the file held the pixel, 0 in a hole) and every channel 0 in the
    holes, alpha included (:func:`envconv.io.read`). The resampling kernel knows nothing of
    holes, so ``valid`` is resampled as one more channel, V (the fraction of each output
    pixel's samples that fell on held pixels, weighted as the colour is), and then:

    - every channel but alpha is divided by V where V > 0, and set to 0 where V = 0: its
      value is the mean over the samples that fell on held pixels, so a hole reads as a hole,
      not as black sky darkening its rim (exact for the nearest and bilinear filters, whose
      weights are non-negative; the bicubic filter's clamped taps make it approximate);
    - alpha is not divided. Without ``alpha=True`` it is the source's alpha resampled (0 in
      holes), i.e. the coverage of held pixels; with ``alpha=True`` it is the output layout's
      coverage times V: the part of the pixel that both has directions and held data.

    Every MIP level is treated alike (its V is the block average of level 0's).
Parts
    A map read from several parts (``EnvMap.parts``) keeps them: the output has the same
    parts, and an alpha channel that ``alpha=True`` adds joins the first part.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..envmap import EnvMap

__all__ = ["convert_with_holes", "VALID_CHANNEL"]

#: Name of the channel that carries ``EnvMap.valid`` through the resampler.
VALID_CHANNEL = "envconv.valid"


def convert_with_holes(envmap: EnvMap, to, resample, **kwargs) -> EnvMap:
    """``resample(envmap, to, **kwargs)`` (the resampler of :func:`envconv.resample.convert.convert`),
    with ``envmap``'s holes and parts handled as the module docstring says."""
    convert = resample
    if envmap.valid is None:
        return _keep_parts(convert(envmap, to, **kwargs), envmap.parts)
    carrier = dataclasses.replace(
        envmap,
        pixels=np.concatenate([envmap.pixels, envmap.valid[:, :, None]], axis=2),
        channels=(*envmap.channels, VALID_CHANNEL),
        valid=None,
        parts=(),
        levels=None,
    )
    out = convert(carrier, to, **kwargs)
    v = out.channels.index(VALID_CHANNEL)
    alpha = out.alpha_index
    levels = [
        _fill_holes(level, v, alpha, bool(kwargs.get("alpha")))
        for level in out.levels or [out.pixels]
    ]
    channels = tuple(c for k, c in enumerate(out.channels) if k != v)
    result = dataclasses.replace(out, pixels=levels[0], channels=channels,
                                 levels=levels if out.levels is not None else None)  # fmt: skip
    return _keep_parts(result, envmap.parts)


def _fill_holes(level: np.ndarray, v: int, alpha: int | None, coverage_alpha: bool) -> np.ndarray:
    """One level without its V channel (index ``v``): channels divided by V, alpha as the
    module docstring says."""
    held = level[:, :, v]
    safe = np.where(held > 0, held, np.float32(1))
    out = np.empty((*level.shape[:2], level.shape[2] - 1), np.float32)
    k = 0
    for c in range(level.shape[2]):
        if c == v:
            continue
        if c == alpha:
            out[:, :, k] = level[:, :, c] * held if coverage_alpha else level[:, :, c]
        else:
            out[:, :, k] = np.where(held > 0, level[:, :, c] / safe, np.float32(0))
        k += 1
    return out


def _keep_parts(out: EnvMap, parts) -> EnvMap:
    """``out`` with the source's ``parts``; an alpha channel the resampler appended after the
    parts' channels moves to the end of the first part."""
    if not parts:
        return out
    held = sum(len(names) for _, names in parts)
    if len(out.channels) == held:
        return dataclasses.replace(out, parts=parts)
    at = len(parts[0][1])
    order = [*range(at), held, *range(at, held)]  # the appended channel is the last

    def move(pixels: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(pixels[:, :, order])

    parts = ((parts[0][0], (*parts[0][1], out.channels[held])), *parts[1:])
    levels = None if out.levels is None else [move(level) for level in out.levels]
    pixels = levels[0] if levels else move(out.pixels)
    return dataclasses.replace(out, pixels=pixels, channels=tuple(out.channels[k] for k in order),
                               levels=levels, parts=parts)  # fmt: skip
