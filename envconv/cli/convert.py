"""``envconv convert IN OUT --to LAYOUT``: read, resample, write."""

from __future__ import annotations

import click

from .main import cli
from .messages import echo_result
from .options import (
    color_options,
    echo_document,
    json_option,
    no_clobber_option,
    read_options,
    resample_options,
    split_options,
    write_options,
)

__all__ = ["convert_command"]


@cli.command("convert")
@click.argument("input_path", metavar="INPUT")
@click.argument("output_path", metavar="OUTPUT")
@read_options
@color_options
@resample_options
@write_options
@no_clobber_option
@click.option(
    "--preview",
    "preview",
    metavar="PNG",
    help="Also write a tone-mapped 8-bit picture of the output (auto exposure, ACES SDR view; see docs/check-a-map.md).",
)
@click.option("--dry-run", is_flag=True, help="Print what would be written; write nothing.")
@json_option
def convert_command(input_path, output_path, dry_run, as_json, preview, no_clobber, **options):
    """Convert INPUT to layout --to and write OUTPUT.

    Multi-file layouts (cube-faces, paraboloid-split) take {face} in the path. Resampling
    runs in scene-linear float32: the input is converted from its colour space and the
    output to --output-colorspace (see docs/color.md). Warnings go to stderr. This is the
    chain `read INPUT resample --to ... write OUTPUT`: the same engine, the same results.

    Before any work, envconv refuses an OUTPUT (or --preview) that is the input (also through
    a link) or that is written twice, and with -n an OUTPUT that exists; otherwise an existing
    file is replaced atomically (a temporary file renamed into place). Missing output
    directories are created.

    \b
    Example:
      envconv convert sky.exr sky_cross.exr --to cube-vcross --size 512
      envconv convert sky.exr sky.png --to latlong --exposure -1 --dry-run
      envconv convert sky.exr 'sky_{face}.exr' --to cube-faces --size 256 --json
    """
    from ..engine.api import convert_record, plan_convert

    read_kw, resample_kw, write_kw, color_kw = split_options(options, with_color=True)
    write_kw["no_clobber"] = no_clobber
    if dry_run and not as_json:
        plan = plan_convert(input_path, output_path, read_kw, resample_kw, write_kw, color_kw)
        _echo_plan(plan)
        return
    from .progress import ResampleProgress

    warnings: list[str] = []
    try:
        with ResampleProgress():
            record = convert_record(input_path, output_path, read=read_kw, resample=resample_kw,
                                    write=write_kw, color=color_kw, warnings=warnings,
                                    preview=preview, dry_run=dry_run)  # fmt: skip
    finally:
        for message in warnings:
            click.echo(f"envconv: warning: {message}", err=True)
    if as_json:
        echo_document("convert", [record], record["seconds"], dry_run=dry_run)
        return
    for path in record["outputs"]:
        echo_result(path)


def _echo_plan(plan: dict) -> None:
    """The dry-run report: one line per fact, then the files that would be written."""
    compression = plan["compression"] or "format default"
    echo_result(f"layout: {plan['layout']}")
    echo_result(f"size: {plan['size']} ({plan['width']}x{plan['height']} per file, "
               f"guard {plan['guard']}, {plan['levels']} level(s))")  # fmt: skip
    echo_result(f"channels: {','.join(plan['channels'])}")
    echo_result(f"bit depth: {plan['bit_depth']} (compression: {compression})")
    echo_result(f"colour: {plan['input_colorspace']} -> {plan['working_colorspace']} (working) "
               f"-> {plan['output_colorspace']}")  # fmt: skip
    for path in plan["files"]:
        echo_result(f"would write: {path}")
