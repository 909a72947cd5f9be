"""``envconv pattern OUT --to LAYOUT``: write the labelled orientation test pattern."""

from __future__ import annotations

import click

from .main import cli
from .messages import echo_result
from .options import (
    layout_choice,
    parse_guard,
    parse_size,
    split_options,
    view_options,
    write_options,
)

__all__ = ["pattern_command"]


@cli.command("pattern")
@click.argument("output_path", metavar="OUTPUT")
@click.option("--to", "to", required=True, type=layout_choice(), help="Layout to draw.")
@click.option(
    "--size",
    default="256",
    callback=parse_size,
    show_default=True,
    metavar="N|WxH",
    help="N: face edge, lat-long height, disk diameter (a perspective view's height, or WxH).",
)
@click.option(
    "--samples",
    type=click.IntRange(1, 16),
    default=2,
    show_default=True,
    help="S×S antialiasing sub-samples per pixel.",
)
@click.option(
    "--out-convention",
    "convention",
    metavar="NAME|AXES",
    help="Draw for another tool's convention (blender, cmft, skylibs, unity, unreal, ffmpeg, mitsuba, ...), or with --to cube-faces a skybox face set (quake, unity-6sided, threejs, godot, unreal).",
)
@click.option(
    "--guard",
    default=None,
    callback=parse_guard,
    metavar="G|fill",
    help="Guard ring of G pixels, or 'fill'.",
)
@click.option("--alpha", is_flag=True, help="Add an alpha channel: valid-region coverage.")
@view_options
@write_options
def pattern_command(output_path, to, size, samples, convention, guard, alpha, fov, yaw, pitch,
                    roll, **options):  # fmt: skip
    """Write a labelled test pattern in layout --to to OUTPUT.

    The pattern marks +X -X +Y -Y +Z -Z with upright, unmirrored labels (as a camera at the
    centre sees them), draws a 15° latitude/longitude grid and the cube-face edges, and tints
    each direction by its coordinates (+X red, +Y green, +Z blue). Load it in an engine to
    check orientation in one look. Multi-file layouts take {face} in the path.

    \b
    Example:
      envconv pattern grid.exr --to latlong --size 512
      envconv pattern sky_{face}.png --to cube-faces --size 256 --out-convention unity
      envconv pattern sky_{face}.tga --to cube-faces --out-convention quake
      envconv pattern view.png --to perspective --size 640x480 --fov 100 --yaw 45
    """
    from .. import io
    from ..engine.api import route_face_sets
    from ..resample.options import output_layout
    from ..views.pattern import render_pattern

    _, _, write_kw = split_options(options)
    resample_kw = {"to": to, "out_convention": convention}
    route_face_sets(output_path, {}, resample_kw, write_kw)
    io.output_paths(to, output_path, faces=write_kw.get("faces"))
    layout, n = output_layout(None, to, size, fov, yaw, pitch, roll)  # size is never None here
    envmap = render_pattern(layout, n, samples, resample_kw.get("out_convention"), guard, alpha)
    for path in io.write(envmap, output_path, **write_kw):
        echo_result(path)
