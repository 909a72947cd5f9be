"""Options shared by several commands, grouped by the library call they feed.

Each group is a list of click decorators whose parameter names equal the keyword arguments of
the library function they are passed to: ``READ`` → :func:`envconv.io.read`, ``RESAMPLE`` →
:func:`envconv.resample.convert`, ``WRITE`` → :func:`envconv.io.write`. A command splits its
keyword arguments with :func:`split_options`. Layout choices come from the registry.
"""

from __future__ import annotations

import click

from ..layouts import layout_names
from ..resample import FILTERS

__all__ = [
    "layout_choice",
    "read_options",
    "resample_options",
    "write_options",
    "split_options",
    "READ",
    "RESAMPLE",
    "WRITE",
]


def layout_choice() -> click.Choice:
    return click.Choice(layout_names(), case_sensitive=False)


def parse_samples(ctx, param, value):
    if value is None or value == "auto":
        return "auto"
    try:
        number = int(value)
    except ValueError:
        raise click.BadParameter(f"expected a positive integer or 'auto', got {value!r}") from None
    if not 1 <= number <= 64:
        raise click.BadParameter(f"expected 1..64 or 'auto', got {number}")
    return number


def parse_guard(ctx, param, value):
    if value is None:
        return 0
    if value == "fill":
        return "fill"
    try:
        number = int(value)
    except ValueError:
        raise click.BadParameter(f"expected pixels (an integer) or 'fill', got {value!r}") from None
    if number < 0:
        raise click.BadParameter(f"expected a non-negative integer or 'fill', got {number}")
    return number


# Each entry: (library keyword, click decorator).
READ = [
    ("layout", click.option("--from", "layout", type=layout_choice(), help="Input layout (default: detect from metadata or aspect).")),
    ("level", click.option("--level", type=click.IntRange(min=0), default=0, show_default=True, help="MIP level of the input to read.")),
]  # fmt: skip

RESAMPLE = [
    ("to", click.option("--to", "to", required=True, type=layout_choice(), help="Output layout.")),
    ("size", click.option("--size", type=click.IntRange(min=1), help="Output N (face edge, height, diameter); default keeps the input's horizon resolution.")),
    ("samples", click.option("--samples", default="auto", callback=parse_samples, show_default=True, help="Sub-samples per pixel edge S (S×S per pixel), or 'auto' from the size ratio.")),
    ("filter", click.option("--filter", "filter", type=click.Choice(list(FILTERS)), default="bilinear", show_default=True, help="Reconstruction filter for source reads.")),
    ("rotate", click.option("--rotate", metavar="YAW,PITCH,ROLL", help="Rotate the environment, degrees: about +Y, then +X, then +Z (right-hand rule).")),
    ("alpha", click.option("--alpha", is_flag=True, help="Add an alpha channel: each pixel's coverage of the valid region.")),
    ("guard", click.option("--guard", default=None, callback=parse_guard, metavar="G|fill", help="Guard ring of G pixels around every cell, or 'fill' for the whole image.")),
]  # fmt: skip

WRITE: list = []


def _apply(group):
    def decorate(fn):
        for _, decorator in reversed(group):
            fn = decorator(fn)
        return fn

    return decorate


read_options = _apply(READ)
resample_options = _apply(RESAMPLE)
write_options = _apply(WRITE)


def split_options(options: dict) -> tuple[dict, dict, dict]:
    """Split a command's keyword arguments into (read, resample, write) keyword dicts."""
    groups = ({k for k, _ in READ}, {k for k, _ in RESAMPLE}, {k for k, _ in WRITE})
    return tuple({k: v for k, v in options.items() if k in names} for names in groups)  # type: ignore[return-value]
