"""``envconv info INPUT``: what an image file is, whether or not it is an environment map."""

from __future__ import annotations

import json

import click

from ..limits import check_level
from .main import cli
from .messages import echo_result
from .options import layout_choice, limited

__all__ = ["info_command"]


@cli.command("info")
@click.argument("input_path", metavar="INPUT")
@click.option("--from", "from_", type=layout_choice(), help="Input layout (default: detect).")
@click.option("--level", default=0, callback=limited(check_level), metavar="INTEGER", help="MIP level to read.")  # fmt: skip
@click.option(
    "--part", metavar="NAME", help="Part of a multi-part file to describe alone (name or index)."
)
@click.option(
    "--stats", is_flag=True, help="Also read the pixels: value range, NaN/Inf count, mean radiance."
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
def info_command(input_path, from_, level, part, stats, as_json):
    """Describe INPUT, any image: layout, size, windows, channels, parts, colour space, metadata.

    Only the headers are read (milliseconds, whatever the size) unless --stats is given,
    which reads the pixels for the value range, the NaN/Inf count and the mean radiance
    (of a map: weighted by each pixel's solid angle over the valid region). An image no
    layout fits is still described, with layout 'unknown' and the candidates and reason.

    \b
    Example:
      envconv info sky.exr --json
      envconv info sky.exr --stats
    """
    from ..views.info import describe

    record = describe(input_path, layout=from_, level=level, part=part, stats=stats)
    if as_json:
        echo_result(json.dumps(record, indent=2, default=str))
        return
    for key, value in record.items():
        if isinstance(value, dict):
            echo_result(f"{key}:")
            for k, v in value.items():
                echo_result(f"  {k}: {v}")
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            echo_result(f"{key}:")
            for item in value:
                echo_result("  - " + ", ".join(f"{k}: {v}" for k, v in item.items()))
        else:
            echo_result(f"{key}: {value}")
