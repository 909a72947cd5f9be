"""Chained steps: ``envconv read IN resample --to L write OUT …``.

Each command returns a step object of :mod:`envconv.engine.pipeline`; the group's result callback
hands the list to :func:`envconv.cli.compose.run_chain`, which validates the whole chain before
reading a pixel and then runs it (or, after ``batch``, runs it once per input).
"""

from __future__ import annotations

import click

from ..engine.pipeline import Colorspace, Exposure, Read, Resample, Rotate, Write
from .main import cli
from .options import (
    color_options,
    no_clobber_option,
    read_options,
    resample_options,
    split_options,
    write_options,
)

__all__ = ["read_step", "rotate_step", "exposure_step", "colorspace_step", "resample_step",
           "write_step"]  # fmt: skip

# Negative numbers (rotate -90, exposure -1.5) must reach the argument, not the option parser.
_NUMBERS = {"ignore_unknown_options": True}


@cli.command("read")
@click.argument("input_path", metavar="[INPUT]", required=False)
@read_options
@color_options
def read_step(input_path, **options):
    """Read INPUT as the source of the steps that follow.

    After `batch` the INPUT is left out: each batch input is read with these options.
    NaN/Inf, --exposure and --clamp-negative are handled right after reading, as in `convert`.

    \b
    Example:
      envconv read sky.exr --from latlong resample --to cube-vcross write cross.exr
    """
    read, _, _, prepare = split_options(options, with_color=True)
    return Read(input_path, **read, **prepare)


@cli.command("rotate", context_settings=_NUMBERS)
@click.argument("angles", metavar="[YAW,PITCH,ROLL]", required=False)
@click.option("--yaw", type=float, help="Degrees about +Y.")
@click.option("--pitch", type=float, help="Degrees about +X (after yaw).")
@click.option("--roll", type=float, help="Degrees about +Z (after pitch).")
def rotate_step(angles, yaw, pitch, roll):
    """Rotate the source: YAW about +Y, then PITCH about +X, then ROLL about +Z (degrees).

    No pixels are filtered here: the rotation is applied inside each later resample.

    \b
    Example:
      envconv read sky.exr rotate -90,0,0 resample --to cube-vcross write cross.exr
    """
    given = [a for a in (yaw, pitch, roll) if a is not None]
    if angles is not None and given:
        raise click.UsageError("give YAW,PITCH,ROLL or --yaw/--pitch/--roll, not both")
    if angles is None:
        return Rotate(yaw=yaw or 0.0, pitch=pitch or 0.0, roll=roll or 0.0)
    return Rotate(angles)


@cli.command("exposure", context_settings=_NUMBERS)
@click.argument("stops", type=float)
def exposure_step(stops):
    """Scale colour (not alpha) by 2**STOPS.

    Between a resample and its first write: that output only. Elsewhere: the source and the
    latest output, so a later write without a resample writes the latest output changed.

    \b
    Example:
      envconv read sky.exr exposure -2 resample --to latlong --size 256 write dim.exr
    """
    return Exposure(stops)


@cli.command("colorspace")
@click.option("--to", "dst", required=True, help="Colour space to convert to.")
@click.option("--from", "src", help="Colour space of the data (default: the file's).")
@click.option("--ocio-config", "config", metavar="PATH", help="OpenColorIO config.")
def colorspace_step(dst, src, config):
    """Convert colour through OpenColorIO (same rule as exposure: see `exposure --help`).

    A later write keeps this colour space and tags the file with it, unless the write gives
    --output-colorspace.

    \b
    Example:
      envconv read sky.exr resample --to latlong write lin.exr \\
              resample --to latlong --size 256 colorspace --to sRGB write preview.png
    """
    return Colorspace(dst, src=src, config=config)


@cli.command("resample")
@resample_options
def resample_step(**options):
    """Resample the source (never a previous output) into layout --to.

    \b
    Example:
      envconv read sky.exr resample --to paraboloid --size 256 --alpha --guard 2 write p.exr
    """
    return Resample(**split_options(options)[1])


@cli.command("write")
@click.argument("output_path", metavar="OUTPUT")
@write_options
@no_clobber_option
@click.option(
    "--preview",
    "preview",
    metavar="PNG",
    help="Also write a tone-mapped 8-bit picture of what is written (same path variables; see docs/check-a-map.md).",
)
def write_step(output_path, preview, no_clobber, **options):
    """Write the latest output (the last resample, or the source) to OUTPUT.

    OUTPUT may use {stem} {name} {ext} {dir} of the input, {layout} and {size} of the output,
    and {face} for multi-file layouts. After a colorspace step the file keeps that colour space
    (and is tagged with it) unless --output-colorspace is given.

    Before any work the chain is refused if an output is an input (also through a link) or two
    outputs share a path, and with -n if an output exists; otherwise an existing file is
    replaced atomically (written to a temporary file, then renamed).

    \b
    Example:
      envconv read sky.exr resample --to cube-faces --size 256 write '{stem}_{face}.exr'
      envconv read sky.exr resample --to cube-vcross write cross.exr --preview cross.png
    """
    return Write(output_path, preview=preview, no_clobber=no_clobber, **split_options(options)[2])
