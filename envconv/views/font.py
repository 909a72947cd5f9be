"""A tiny 5×7 bitmap font and a numpy text renderer, for labels on preview pictures.

No font file or font library is needed: every glyph is a 5 × 7 table of ink ("#") and paper
(" "), top row first, as the reader sees it. Lower-case letters are drawn as capitals;
characters without a glyph are drawn as "?". Each character advances 6 font pixels (one
column of spacing); a line is 7 font pixels tall. The glyphs of ``+ - X Y Z`` are those of
:data:`envconv.views.pattern.FONT`, so sheet labels match the test pattern's.
"""

from __future__ import annotations

import numpy as np

from .pattern import FONT as _PATTERN_FONT

__all__ = ["FONT", "text_mask", "draw_text", "text_width"]

_ROWS = """
A  ###  #   # #   # ##### #   # #   # #   #
B ####  #   # #   # ####  #   # #   # ####
C  ###  #   # #     #     #     #   #  ###
D ####  #   # #   # #   # #   # #   # ####
E ##### #     #     ####  #     #     #####
F ##### #     #     ####  #     #     #
G  ###  #   # #     # ### #   # #   #  ####
H #   # #   # #   # ##### #   # #   # #   #
I  ###    #     #     #     #     #    ###
J   ###    #     #     #     #  #  #   ##
K #   # #  #  # #   ##    # #   #  #  #   #
L #     #     #     #     #     #     #####
M #   # ## ## # # # # # # #   # #   # #   #
N #   # ##  # # # # #  ## #   # #   # #   #
O  ###  #   # #   # #   # #   # #   #  ###
P ####  #   # #   # ####  #     #     #
Q  ###  #   # #   # #   # # # # #  #   ## #
R ####  #   # #   # ####  # #   #  #  #   #
S  #### #     #      ###      #     # ####
T #####   #     #     #     #     #     #
U #   # #   # #   # #   # #   # #   #  ###
V #   # #   # #   # #   # #   #  # #    #
W #   # #   # #   # # # # # # # ## ## #   #
0  ###  #   # #  ## # # # ##  # #   #  ###
1   #    ##     #     #     #     #    ###
2  ###  #   #     #    #    #    #    #####
3 ####      #     #  ###      #     # ####
4    #    ##   # #  #  #  #####    #     #
5 ##### #     ####      #     # #   #  ###
6  ###  #     #     ####  #   # #   #  ###
7 #####     #    #    #    #     #     #
8  ###  #   # #   #  ###  #   # #   #  ###
9  ###  #   # #   #  ####     #     #  ###
.                               ##    ##
,                               ##     #    #
:       ##    ##                ##    ##
(    #    #    #     #     #      #     #
)  #      #     #     #     #    #    #
/           #    #    #    #    #
=             #####       #####
[  ###   #     #     #     #     #     ###
]  ###     #     #     #     #     #   ###
_                                     #####
"""


_EXTRA = {
    "%": ("##   ", "##  #", "   # ", "  #  ", " #   ", "#  ##", "   ##"),
    "°": (" ##  ", "#  # ", " ##  ", "     ", "     ", "     ", "     "),
    "?": (" ### ", "#   #", "    #", "   # ", "  #  ", "     ", "  #  "),
}


def _parse() -> dict[str, tuple[str, ...]]:
    font = {" ": ("     ",) * 7}
    for line in _ROWS.strip("\n").splitlines():
        ch, body = line[0], line[2:].ljust(41)
        font[ch] = tuple(body[6 * k : 6 * k + 5].ljust(5) for k in range(7))
    font.update(_PATTERN_FONT)
    font.update(_EXTRA)
    return font


#: Character → seven rows of five cells, "#" = ink.
FONT = _parse()
_GLYPHS = {ch: np.array([[c == "#" for c in row] for row in rows]) for ch, rows in FONT.items()}


def text_width(text: str, scale: int = 1) -> int:
    """Width in pixels of ``text`` drawn at ``scale`` image pixels per font pixel."""
    return max(6 * len(text) - 1, 0) * scale


def text_mask(text: str, scale: int = 1) -> np.ndarray:
    """Boolean ink mask, shape (7·scale, text_width(text, scale)), of one line of text."""
    mask = np.zeros((7, max(6 * len(text) - 1, 0)), bool)
    for k, ch in enumerate(text):
        glyph = _GLYPHS.get(ch, _GLYPHS.get(ch.upper(), _GLYPHS["?"]))
        mask[:, 6 * k : 6 * k + 5] = glyph
    return np.repeat(np.repeat(mask, scale, axis=0), scale, axis=1)


def draw_text(image: np.ndarray, text: str, x: int, y: int, colour, scale: int = 1) -> None:
    """Draw ``text`` into ``image`` (H, W, C) in place, top-left corner at column x, row y.

    Ink falling outside the image is dropped. ``colour`` is one value per channel.
    """
    mask = text_mask(text, scale)
    h, w = image.shape[:2]
    x0, y0 = max(x, 0), max(y, 0)
    x1, y1 = min(x + mask.shape[1], w), min(y + mask.shape[0], h)
    if x1 <= x0 or y1 <= y0:
        return
    sub = mask[y0 - y : y1 - y, x0 - x : x1 - x]
    image[y0:y1, x0:x1][sub] = colour
