"""``envconv view INPUT [-o PAGE] [--open]``: a self-contained WebGL2 page to look around in."""

from __future__ import annotations

import os

import click

from .main import cli
from .messages import echo_result
from .options import layout_choice, refuse_overwrite

__all__ = ["view_command"]


def _default_output(input_path: str) -> str:
    from ..io.face_files import face_path

    stem = os.path.splitext(os.path.basename(face_path(input_path, "")))[0].rstrip("_.-")
    return f"{stem or 'envmap'}.view.html"


@cli.command("view")
@click.argument("input_path", metavar="INPUT")
@click.option(
    "-o",
    "--output",
    "output_path",
    metavar="HTML",
    help="Page to write (default: INPUT's name + .view.html, in the current directory).",
)
@click.option("--open", "open_page", is_flag=True, help="Open the page in the default browser.")
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
    "--input-colorspace", "input_colorspace", metavar="NAME", help="OCIO colour space of the input."
)
@click.option(
    "--cap",
    type=click.IntRange(16, 4096),
    default=1024,
    show_default=True,
    help="Height cap of the embedded lat-long (width twice this).",
)
def view_command(input_path, output_path, open_page, layout, in_convention, input_colorspace, cap):  # fmt: skip
    """Write one HTML page (no network needed to view it) to look around inside INPUT: drag
    to turn, wheel to zoom, a mirror, a GGX rough (roughness slider) and a diffuse ball, exposure, ACES tone curve, horizon grid,
    axis labels and a convention selector that shows the map as that tool would.

    \b
    Example:
      envconv view sky.exr --open
      envconv view sky_{face}.png -o sky.html
    """
    from .. import io
    from ..io.picture import write_page
    from ..views.viewer import build_page

    output_path = output_path or _default_output(input_path)
    refuse_overwrite(input_path, output_path)
    envmap = io.read(input_path, layout=layout, input_colorspace=input_colorspace)
    page = build_page(envmap, os.path.basename(input_path), in_convention, cap)
    echo_result(write_page(page, output_path))
    if open_page:
        import webbrowser

        webbrowser.open("file://" + os.path.abspath(output_path))
