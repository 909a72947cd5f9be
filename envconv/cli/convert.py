"""``envconv convert IN OUT --to LAYOUT``: read, resample, write."""

from __future__ import annotations

import click

from .main import cli
from .options import read_options, resample_options, split_options, write_options

__all__ = ["convert_command"]


@cli.command("convert")
@click.argument("input_path", metavar="INPUT")
@click.argument("output_path", metavar="OUTPUT")
@read_options
@resample_options
@write_options
def convert_command(input_path, output_path, **options):
    """Convert INPUT to layout --to and write OUTPUT.

    Multi-file layouts (cube-faces, paraboloid-split) take {face} in the path.

    \b
    Example:
      envconv convert sky.exr sky_cross.exr --to cube-vcross --size 512
    """
    from ..api import convert_file

    read_kw, resample_kw, write_kw = split_options(options)
    for path in convert_file(
        input_path, output_path, read=read_kw, resample=resample_kw, write=write_kw
    ):
        click.echo(path)
