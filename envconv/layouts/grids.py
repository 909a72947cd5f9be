"""Sample grids of a lat-long: where a W × H image's samples sit, and moving between grids.

envconv's lat-long (docs/geometry.md) is sampled at pixel centres. Some readers and writers put
the samples on the image's edges instead, so that the first and last rows lie on the poles
(and, for OpenEXR, the first and last columns both on the seam). The *grid* names where
sample (i, j) of a W × H lat-long sits in (u, v); the direction of (u, v) is envconv's formula
in every case (lon = 2π(0.5 − u), lat = π(0.5 − v)):

=============  ===========================  ==========================  ========================
grid           u of column i                v of row j                  who
=============  ===========================  ==========================  ========================
``centres``    (i + 0.5) / W                (j + 0.5) / H               envconv, OIIO (default),
                                                                        GPU samplers, Blender
``edge-rows``  (i + 0.5) / W                j / (H − 1)                 Mitsuba 3 ``envmap``
``edges``      i / (W − 1)                  j / (H − 1)                 OpenEXR ``ImfEnvmap``,
                                                                        ``maketx --envlatl``,
                                                                        OIIO ``sampleborder``
=============  ===========================  ==========================  ========================

::

    centres  v=0 +--------+  row 0 at v = 0.5/H     edge-rows  v=0 +--o--o--+  row 0 on the pole
                 |  o  o  |                                        |        |
                 |  o  o  |                                        |  o  o  |  (H − 1 row
                 |  o  o  |                                        |        |   spacings)
             v=1 +--------+  row H−1 at 1 − 0.5/H              v=1 +--o--o--+  row H−1 on the pole

Moving between grids is a separable linear interpolation, rows then columns: exact for
constants and for functions linear in u and v, otherwise within h²/8 times the second
derivative (h the sample spacing). :func:`to_centres` interpolates between the file's samples;
:func:`from_centres` interpolates envconv's pixels at the other grid's positions, continuing the
map past its ends as docs/geometry.md does (columns wrap; a row past a pole is the first or last
row turned half a turn, i.e. on the opposite meridian), so a sample on a pole is the mean of
the two pixels facing each other across it.
"""

from __future__ import annotations

import numpy as np

from ..errors import LayoutError, UsageError

__all__ = ["GRIDS", "CENTRES", "GRID_TAG", "check_grid", "sample_positions", "to_centres",
           "from_centres", "tagged_grid"]  # fmt: skip

CENTRES = "centres"
#: Grid name → (rows on the edges, columns on the edges).
GRIDS: dict[str, tuple[bool, bool]] = {
    CENTRES: (False, False),
    "edge-rows": (True, False),
    "edges": (True, True),
}


def check_grid(grid: str) -> tuple[bool, bool]:
    """(rows on edges, columns on edges) of a grid name; UsageError for an unknown one."""
    if grid not in GRIDS:
        raise UsageError(f"unknown lat-long grid {grid!r}; known: {', '.join(GRIDS)}")
    return GRIDS[grid]


def sample_positions(grid: str, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """(u of each column, v of each row) of a ``width`` × ``height`` lat-long on ``grid``.

    Examples
    --------
    >>> u, v = sample_positions("edge-rows", 4, 3)
    >>> u.tolist(), v.tolist()
    ([0.125, 0.375, 0.625, 0.875], [0.0, 0.5, 1.0])
    """
    edge_rows, edge_cols = check_grid(grid)
    return _positions(width, edge_cols), _positions(height, edge_rows)


def _positions(n: int, on_edges: bool) -> np.ndarray:
    if on_edges and n > 1:
        return np.arange(n, dtype=np.float64) / (n - 1)
    return (np.arange(n, dtype=np.float64) + 0.5) / n


def to_centres(pixels: np.ndarray, grid: str) -> np.ndarray:
    """A lat-long stored on ``grid`` (H, W, C), resampled onto envconv's pixel centres.

    Pixel (i, j) of the result holds the file's samples linearly interpolated at envconv's
    centre ((i + 0.5)/W, (j + 0.5)/H): on an axis on the edges, at sample position
    (k + 0.5)(n − 1)/n. An axis of one sample is left as it is.

    Examples
    --------
    >>> edge = np.array([0.0, 1.0, 2.0], np.float32).reshape(3, 1, 1)  # v = 0, 1/2, 1
    >>> [round(float(x), 4) for x in to_centres(edge, "edge-rows")[:, 0, 0]]  # v = 1/6, 1/2, 5/6
    [0.3333, 1.0, 1.6667]
    """
    edge_rows, edge_cols = check_grid(grid)
    out = np.asarray(pixels, np.float32)
    if edge_rows and out.shape[0] > 1:
        j0, t = _inner_weights(out.shape[0])
        t = t[:, None, None]
        out = out[j0] * (1 - t) + out[j0 + 1] * t
    if edge_cols and out.shape[1] > 1:
        i0, t = _inner_weights(out.shape[1])
        t = t[None, :, None]
        out = out[:, i0] * (1 - t) + out[:, i0 + 1] * t
    return np.ascontiguousarray(out, np.float32)


def _inner_weights(n: int) -> tuple[np.ndarray, np.ndarray]:
    """For centre k of n: the left edge-grid sample and the right one's weight."""
    x = (np.arange(n, dtype=np.float64) + 0.5) * (n - 1) / n
    i0 = np.minimum(np.floor(x).astype(np.intp), n - 2)
    return i0, (x - i0).astype(np.float32)


def from_centres(pixels: np.ndarray, grid: str) -> np.ndarray:
    """envconv's lat-long (H, W, C), W even, resampled onto ``grid``'s sample positions.

    Sample (i, j) is envconv's map linearly interpolated at (u_i, v_j) of
    :func:`sample_positions`, with the continued mapping past the image's ends (see the module
    docstring): a pole sample is the mean of row 0 (or H − 1) at lon and at lon + π.

    Examples
    --------
    >>> px = np.arange(8, dtype=np.float32).reshape(2, 4, 1)  # rows [0 1 2 3], [4 5 6 7]
    >>> from_centres(px, "edge-rows")[:, :, 0].tolist()  # the two poles: means across them
    [[1.0, 2.0, 1.0, 2.0], [5.0, 6.0, 5.0, 6.0]]
    """
    edge_rows, edge_cols = check_grid(grid)
    out = np.asarray(pixels, np.float32)
    height, width = out.shape[:2]
    if edge_rows and height > 1:
        half = width // 2
        # Rows -1 and H: rows 0 and H - 1 continued past the poles, on the opposite meridian.
        padded = np.concatenate(
            [np.roll(out[:1], half, axis=1), out, np.roll(out[-1:], half, axis=1)]
        )
        j0, t = _outer_weights(height)
        t = t[:, None, None]
        out = padded[j0] * (1 - t) + padded[j0 + 1] * t
    if edge_cols and width > 1:
        padded = np.concatenate([out[:, -1:], out, out[:, :1]], axis=1)  # columns wrap
        i0, t = _outer_weights(width)
        t = t[None, :, None]
        out = padded[:, i0] * (1 - t) + padded[:, i0 + 1] * t
    return np.ascontiguousarray(out, np.float32)


def _outer_weights(n: int) -> tuple[np.ndarray, np.ndarray]:
    """For edge-grid sample k of n: the left pixel of a grid padded by one on each side (index
    0 is pixel −1) and the right one's weight."""
    x = np.arange(n, dtype=np.float64) * n / (n - 1) + 0.5  # centre index + 1, in [0.5, n + 0.5]
    i0 = np.minimum(np.floor(x).astype(np.intp), n)
    return i0, (x - i0).astype(np.float32)


#: The tag that records a file's grid when it is not envconv's centres.
GRID_TAG = "envconv:grid"


def tagged_grid(metadata) -> str:
    """The grid a map's ``envconv:grid`` tag records (``centres`` when untagged)."""
    grid = str(metadata.get(GRID_TAG, CENTRES) or CENTRES)
    if grid not in GRIDS:
        raise LayoutError(f"the map's {GRID_TAG} tag is {grid!r}, not one of {', '.join(GRIDS)}")
    return grid
