"""``envconv pattern OUT --to LAYOUT``: write the labelled orientation test pattern."""

from __future__ import annotations

import click

from .main import cli
from .options import layout_choice, parse_guard, split_options, write_options

__all__ = ["pattern_command"]


@cli.command("pattern")
@click.argument("output_path", metavar="OUTPUT")
@click.option("--to", "to", required=True, type=layout_choice(), help="Layout to draw.")
@click.option(
    "--size",
    type=click.IntRange(min=1),
    default=256,
    show_default=True,
    help="N: face edge, lat-long height, disk diameter.",
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
@write_options
def pattern_command(output_path, to, size, samples, convention, guard, alpha, **options):
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
    """
    from .. import io
    from ..engine.api import route_face_sets
    from ..views.pattern import render_pattern

    _, _, write_kw = split_options(options)
    resample_kw = {"to": to, "out_convention": convention}
    route_face_sets(output_path, {}, resample_kw, write_kw)
    io.output_paths(to, output_path, faces=write_kw.get("faces"))
    envmap = render_pattern(to, size, samples, resample_kw.get("out_convention"), guard, alpha)
    for path in io.write(envmap, output_path, **write_kw):
        click.echo(path)
