"""Options shared by several commands, with choices taken from the layout registry."""

from __future__ import annotations

import click

from ..layouts import layout_names
from ..resample import FILTERS

__all__ = ["layout_choice", "resample_options", "parse_samples", "parse_guard"]


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


def resample_options(fn):
    """--to, --size, --samples, --filter, --rotate, --alpha, --guard."""
    decorators = [
        click.option("--to", "to", required=True, type=layout_choice(), help="Output layout."),
        click.option("--size", type=click.IntRange(min=1), help="Output N (face edge, height, diameter); default keeps the input's horizon resolution."),
        click.option("--samples", default="auto", callback=parse_samples, show_default=True, help="Sub-samples per pixel edge S (S×S per pixel), or 'auto' from the size ratio."),
        click.option("--filter", "filter_", type=click.Choice(list(FILTERS)), default="bilinear", show_default=True, help="Reconstruction filter for source reads."),
        click.option("--rotate", metavar="YAW,PITCH,ROLL", help="Rotate the environment, degrees: about +Y, then +X, then +Z (right-hand rule)."),
        click.option("--alpha", is_flag=True, help="Add an alpha channel: the pixel's coverage of the valid region."),
        click.option("--guard", default=None, callback=parse_guard, metavar="G|fill", help="Guard ring of G pixels around every cell, or 'fill' for the whole image."),
    ]  # fmt: skip
    for decorator in reversed(decorators):
        fn = decorator(fn)
    return fn
