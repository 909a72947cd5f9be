"""``envconv preview INPUT -o SHEET``: a labelled, tone-mapped contact sheet of a map."""

from __future__ import annotations

import click

from .main import cli
from .messages import echo_result
from .options import layout_choice, refuse_overwrite

__all__ = ["preview_command"]


@cli.command("preview")
@click.argument("input_path", metavar="INPUT")
@click.option(
    "-o",
    "--output",
    "output_path",
    required=True,
    metavar="PNG",
    help="Contact sheet to write (PNG, JPEG, TIFF).",
)
@click.option(
    "--from",
    "layout",
    type=layout_choice(),
    help="Input layout (default: detect from metadata or aspect).",
)
@click.option(
    "--in-convention",
    "in_convention",
    metavar="NAME|AXES",
    help="Convention of the tool that made the input (as for convert).",
)
@click.option(
    "--convention",
    "convention",
    metavar="NAME|AXES",
    help="Show and label the six views in this tool's world axes: blender (Z up), unity, unreal, threejs, ... or a frame as AXES (envconv = A·tool). Default: envconv's (+Y up, right-handed).",
)
@click.option(
    "--exposure",
    type=float,
    default=0.0,
    show_default=True,
    metavar="STOPS",
    help="Stops on top of the automatic exposure (log-average luminance to 0.18).",
)
@click.option(
    "--view",
    type=click.Choice(["tone", "srgb"]),
    default="tone",
    show_default=True,
    help="tone: OCIO's ACES 2.0 SDR view; srgb: un-tone-mapped sRGB.",
)
@click.option(
    "--input-colorspace", "input_colorspace", metavar="NAME", help="OCIO colour space of the input."
)
def preview_command(input_path, output_path, layout, in_convention, convention, exposure, view, input_colorspace):  # fmt: skip
    """Write a contact sheet of INPUT: the map as stored, six 90° views along the world axes
    (envconv's frame: +Y up, right-handed; or --convention's), a mirror ball, a diffuse ball and a line of
    statistics, all with one automatic exposure. Multi-file inputs take {face} in the path.

    \b
    Example:
      envconv preview sky.exr -o sky_sheet.png
      envconv preview blender_sky.exr -o sheet.png --in-convention blender --convention blender
    """
    from .. import io
    from ..errors import UsageError
    from ..io.picture import write_picture
    from ..layouts.conventions import world_frame
    from ..views.preview import contact_sheet

    refuse_overwrite(input_path, output_path)
    try:  # an unknown name is a usage error, found before any reading
        world_frame(convention)
    except UsageError as exc:
        raise click.BadParameter(str(exc), param_hint="--convention") from None
    envmap = io.read(input_path, layout=layout, input_colorspace=input_colorspace)
    sheet = contact_sheet(envmap, exposure, view, in_convention, convention=convention)
    echo_result(write_picture(sheet, output_path))
