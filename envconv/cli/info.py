"""``envconv info INPUT``: layout, size, channels, range and mean radiance."""

from __future__ import annotations

import json

import click

from .main import cli
from .options import layout_choice

__all__ = ["info_command"]


@cli.command("info")
@click.argument("input_path", metavar="INPUT")
@click.option("--from", "from_", type=layout_choice(), help="Input layout (default: detect).")
@click.option("--level", type=click.IntRange(min=0), default=0, help="MIP level to read.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
def info_command(input_path, from_, level, as_json):
    """Describe INPUT: detected layout, size, channels, value range and mean radiance.

    The mean radiance is weighted by each pixel's solid angle over the valid region.

    \b
    Example:
      envconv info sky.exr --json
    """
    from ..info import describe

    record = describe(input_path, layout=from_, level=level)
    if as_json:
        click.echo(json.dumps(record, indent=2, default=str))
        return
    for key, value in record.items():
        if isinstance(value, dict):
            click.echo(f"{key}:")
            for k, v in value.items():
                click.echo(f"  {k}: {v}")
        else:
            click.echo(f"{key}: {value}")
