"""``envconv convert IN OUT --to LAYOUT``: read, resample, write."""

from __future__ import annotations

import click

from .main import cli
from .options import layout_choice, resample_options

__all__ = ["convert_command"]


@cli.command("convert")
@click.argument("input_path", metavar="INPUT")
@click.argument("output_path", metavar="OUTPUT")
@click.option("--from", "from_", type=layout_choice(), help="Input layout (default: detect).")
@resample_options
def convert_command(
    input_path, output_path, from_, to, size, samples, filter_, rotate, alpha, guard
):
    """Convert INPUT to layout --to and write OUTPUT.

    Multi-file layouts (cube-faces, paraboloid-split) take {face} in the path.

    \b
    Example:
      envconv convert sky.exr sky_cross.exr --to cube-vcross --size 512
    """
    from .. import io
    from ..resample import convert

    io.output_paths(to, output_path)  # fail on a bad output path before any work
    source = io.read(input_path, layout=from_)
    result = convert(
        source,
        to,
        size=size,
        samples=samples,
        filter=filter_,
        rotate=rotate,
        guard=guard,
        alpha=alpha,
    )
    for path in io.write(result, output_path):
        click.echo(path)
