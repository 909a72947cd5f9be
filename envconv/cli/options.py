"""Options shared by several commands, grouped by the library call they feed.

Each group is a list of click decorators whose parameter names equal the keyword arguments of
the library function they are passed to: ``READ`` → :func:`envconv.io.read`, ``RESAMPLE`` →
:func:`envconv.resample.convert.convert`, ``WRITE`` → :func:`envconv.io.write`, ``COLOR`` →
:func:`envconv.color.prepare.prepare_input`. A command splits its
keyword arguments with :func:`split_options`. Layout choices come from the registry.
"""

from __future__ import annotations

import click

from ..errors import LayoutError
from ..layouts import layout_names, resolve_layout_name
from ..limits import check_level, check_stops
from ..resample.convert import FILTERS
from .messages import echo_result

__all__ = [
    "json_option",
    "echo_document",
    "limited",
    "refuse_overwrite",
    "no_clobber_option",
    "layout_choice",
    "LayoutChoice",
    "read_options",
    "resample_options",
    "write_options",
    "color_options",
    "split_options",
    "view_options",
    "parse_size",
    "READ",
    "RESAMPLE",
    "WRITE",
    "COLOR",
]


class LayoutChoice(click.Choice):
    """A layout name: a registered one, any case, or an alias (``equirect``); a typo is
    answered with the close names, a family word (``cubemap``) with its layouts."""

    def convert(self, value, param, ctx):
        try:
            return resolve_layout_name(value)
        except LayoutError as exc:
            self.fail(str(exc), param, ctx)


def layout_choice() -> click.Choice:
    return LayoutChoice(layout_names(), case_sensitive=False)


def _checked(check, value):
    """``check(value)`` (a check of :mod:`envconv.resample.options`), its UsageError as click's."""
    from ..errors import UsageError

    try:
        return check(value)
    except UsageError as exc:
        raise click.BadParameter(str(exc)) from None


def limited(check):
    """A click callback running one of :mod:`envconv.limits`'s checks (None passes)."""

    def callback(ctx, param, value):
        return None if value is None else _checked(check, value)

    return callback


def parse_roughness(ctx, param, value):
    """``--roughness``: a mapping name or ``R1,R2,…`` in [0, 1], checked before any work."""
    from ..resample.options import check_roughness

    _checked(check_roughness, value)
    return value


def parse_samples(ctx, param, value):
    if value is None or value == "auto":
        return "auto"
    from ..resample.options import check_samples

    return _checked(check_samples, value)


def parse_size(ctx, param, value):
    """``--size N`` (an int) or ``--size WxH`` (a perspective view's; kept as text)."""
    if value is None:
        return None
    from ..resample.options import check_size

    n, width = _checked(check_size, value)
    return n if width is None else f"{width}x{n}"


def parse_guard(ctx, param, value):
    if value is None:
        return 0
    if value == "fill":
        return "fill"
    from ..resample.options import check_guard

    return _checked(check_guard, value)


def parse_mips(ctx, param, value):
    """``--mips`` alone (or ``--mips all``): the full chain; ``--mips K``: K levels;
    ``--mips ggx`` (``ggx:K``): the GGX-prefiltered chain (``box`` is the default filter)."""
    if value is None:
        return None
    from ..resample.options import check_mips

    text = str(value)
    levels, ggx = _checked(check_mips, int(text) if text.isdigit() else text)
    return text if ggx else levels


_OCIO_CONFIG = (
    "ocio_config",
    click.option(
        "--ocio-config",
        "ocio_config",
        metavar="PATH",
        help="OpenColorIO config (default: $OCIO, else OCIO's built-in ocio://default).",
    ),
)

# Each entry: (library keyword, click decorator).
READ = [
    ("layout", click.option("--from", "layout", type=layout_choice(), help="Input layout (default: detect from metadata or aspect).")),
    ("level", click.option("--level", default=0, callback=limited(check_level), show_default=True, metavar="INTEGER", help="MIP level of the input to read.")),
    ("part", click.option("--part", metavar="NAME", help="Part of a multi-part input to read alone, by name or index (default: every part of the first part's windows).")),
    ("input_colorspace", click.option("--input-colorspace", "input_colorspace", metavar="NAME", help="OCIO colour space of the input (default: its oiio:ColorSpace, else linear for float, sRGB for 8/16-bit).")),
    _OCIO_CONFIG,
]  # fmt: skip

RESAMPLE = [
    ("to", click.option("--to", "to", required=True, type=layout_choice(), help="Output layout.")),
    ("size", click.option("--size", callback=parse_size, metavar="N|WxH", help="Output N: face edge, lat-long height, disk diameter (docs/geometry.md, 'Sizes'); a perspective view's height, or its WxH. Default: the N that keeps the input's pixel pitch along the horizon (a 2048x1024 lat-long gives cube faces of 559, a lat-long of 1024), a fisheye's or perspective view's at its axis; with --mips, N+2G is then rounded to the nearest power of two (--mips K: multiple of 2^(K-1)), so that every level holds whole cells (559 becomes 512).")),
    ("samples", click.option("--samples", default="auto", callback=parse_samples, show_default=True, help="Sub-samples per pixel edge S (S×S per pixel), or 'auto': per pixel, about two per source texel its edge spans.")),
    ("filter", click.option("--filter", "filter", type=click.Choice(list(FILTERS)), default=None, help="area (the default): each pixel the exact solid-angle mean of the source over its footprint, every texel's energy kept; bilinear, bicubic, nearest: sub-samples read through that filter. A fisheye guard ring that reaches the point behind the view is point-sampled around the view's exact pixels.")),
    ("rotate", click.option("--rotate", metavar="YAW,PITCH,ROLL", help="Rotate the environment, degrees: about +Y, then +X, then +Z (right-hand rule).")),
    ("alpha", click.option("--alpha", is_flag=True, help="Add an alpha channel: each pixel's coverage of the valid region.")),
    ("guard", click.option("--guard", default=None, callback=parse_guard, metavar="G|fill", help="Guard ring of G pixels around every cell, or 'fill' for the whole image.")),
    ("in_convention", click.option("--in-convention", "in_convention", metavar="NAME|AXES", help="Convention of the tool that made the input: blender, cmft, skylibs, unity, unreal, threejs, ffmpeg, openexr, openexr-edges, mitsuba, probe-back, probe-forward, pbrt, ddgi, ddgi-z-up, or an axis remap like -x,z,y; for a {face} input, a skybox face set: quake (source, cube2), unity-6sided, threejs, godot, unreal (found from the file names when omitted; see docs/conventions.md).")),
    ("out_convention", click.option("--out-convention", "out_convention", metavar="NAME|AXES", help="Convention of the tool that will read the output (same names as --in-convention; with --to cube-faces, a face set names and turns the six files).")),
    ("up", click.option("--up", type=click.Choice(["y", "z"], case_sensitive=False), help="Up axis of the input's world; z turns its +Z into +Y (same as --axes=x,z,-y).")),
    ("axes", click.option("--axes", metavar="AXES", help="Remap the input's axes by a signed permutation: --axes=-x,z,y makes envconv's (x, y, z) the input's (-x, z, y).")),
    ("mips", click.option("--mips", is_flag=False, flag_value="all", default=None, callback=parse_mips, metavar="[K|ggx[:K]]", help="Write a mip chain: alone, every level down to 1x1; --mips K, K levels; --mips ggx, GGX-prefiltered levels for image-based lighting. EXR/TIFF/DDS/KTX2: one file; other formats: {level} in the path.")),
    ("roughness", click.option("--roughness", default="gltf", callback=parse_roughness, show_default=True, metavar="gltf|filament|unreal|R1,R2,..", help="Roughness of each --mips ggx level: glTF-IBL-Sampler's k/(L-1), Filament's or Unreal's mapping, or a list for levels 1.. (see docs/ibl.md).")),
    ("irradiance", click.option("--irradiance", is_flag=True, help="Write the cosine-convolved environment E/pi (diffuse image-based lighting) instead of the environment.")),
    ("fov", click.option("--fov", metavar="DEG|H,V", help="Field of view of a fisheye (its diameter; default 180, as ffmpeg) or perspective output (horizontal, or H,V; default 90).")),
    ("yaw", click.option("--yaw", type=float, metavar="DEG", help="Aim a fisheye or perspective output: turn the view right by DEG (as ffmpeg v360's yaw).")),
    ("pitch", click.option("--pitch", type=float, metavar="DEG", help="Aim a fisheye or perspective output: raise the view by DEG (after --yaw).")),
    ("roll", click.option("--roll", type=float, metavar="DEG", help="Bank a fisheye or perspective view right by DEG (after --pitch); the picture turns counter-clockwise.")),
]  # fmt: skip

WRITE = [
    ("bit_depth", click.option("--bit-depth", "bit_depth", type=click.Choice(["half", "float", "uint8", "uint16"]), help="Output pixel type (default: the input's, where the format stores it).")),
    ("compression", click.option("--compression", metavar="NAME", help="EXR: none rle zips zip piz pxr24 b44 b44a dwaa dwab htj2k32 htj2k256 (zip/zips/dwaa/dwab take :LEVEL); TIFF: none lzw zip packbits.")),
    ("output_colorspace", click.option("--output-colorspace", "output_colorspace", metavar="NAME", help="OCIO colour space to write (default: linear Rec.709 for float/half, sRGB for 8/16-bit).")),
    ("dither", click.option("--dither/--no-dither", default=True, show_default=True, help="Dither 8-bit output (deterministic: same input, same file).")),
    _OCIO_CONFIG,
]  # fmt: skip

#: Options of :func:`envconv.color.prepare.prepare_input` (range and NaN/Inf of the source).
COLOR = [
    ("exposure", click.option("--exposure", default=0.0, callback=limited(check_stops), metavar="STOPS", help="Scale colour by 2**STOPS before resampling (e.g. -2 to fit HDR into 8 bits).")),
    ("fix_nonfinite", click.option("--fix-nonfinite", "fix_nonfinite", type=click.Choice(["none", "black", "box3", "error"]), default="none", show_default=True, help="Replace NaN/Inf in the input: with 0, with the mean of finite 3x3 neighbours, or stop.")),
    ("clamp_negative", click.option("--clamp-negative", "clamp_negative", is_flag=True, help="Set negative input values to 0 (kept by default).")),
]  # fmt: skip


def _apply(group):
    def decorate(fn):
        # An option shared by two groups (--ocio-config) is added once per command.
        have = {p.name for p in getattr(fn, "__click_params__", [])}
        for name, decorator in reversed(group):
            if name not in have:
                fn = decorator(fn)
        return fn

    return decorate


read_options = _apply(READ)
resample_options = _apply(RESAMPLE)
#: --fov, --yaw, --pitch, --roll alone (for commands that draw rather than resample).
view_options = _apply([entry for entry in RESAMPLE if entry[0] in ("fov", "yaw", "pitch", "roll")])
write_options = _apply(WRITE)
color_options = _apply(COLOR)


def split_options(options: dict, with_color: bool = False) -> tuple[dict, ...]:
    """Split a command's keyword arguments into (read, resample, write) keyword dicts.

    With ``with_color=True`` a fourth dict holds the ``COLOR`` options (for
    :func:`envconv.color.prepare.prepare_input`). A name in two groups goes to both.
    """
    groups = [{k for k, _ in READ}, {k for k, _ in RESAMPLE}, {k for k, _ in WRITE}]
    if with_color:
        groups.append({k for k, _ in COLOR})
    return tuple({k: v for k, v in options.items() if k in names} for names in groups)


def refuse_overwrite(input_path: str, output_path: str) -> None:
    """Usage error when ``output_path`` is the input, or one file of a ``{face}`` input, also
    through a link (the output policy of :mod:`envconv.engine.outputs`)."""
    from ..engine.outputs import check_outputs, input_files
    from ..errors import UsageError

    try:
        check_outputs([(output_path, False)], input_files(input_path))
    except UsageError as exc:
        raise click.UsageError(str(exc)) from None


#: ``-n/--no-clobber`` of convert, write, run and batch (the output policy: envconv.engine.outputs).
no_clobber_option = click.option("-n", "--no-clobber", "no_clobber", is_flag=True, help="Refuse, before any work, to replace an output that exists (by default it is replaced atomically).")  # fmt: skip


#: ``--json`` of convert, run and batch: one JSON document on stdout, nothing else there.
json_option = click.option("--json", "as_json", is_flag=True, help="Print one JSON document on stdout instead of the paths or the summary: every file written (with --dry-run: that would be) with its layout, size, levels, channels, bytes and timings (docs/shell.md, 'JSON output').")  # fmt: skip


def echo_document(command: str, records: list, seconds: float, events=None,
                  dry_run: bool = False) -> None:  # fmt: skip
    """Print the JSON document of :func:`envconv.engine.records.document` on stdout."""
    import json

    from ..engine.records import document

    echo_result(json.dumps(document(command, records, seconds, events, dry_run), indent=2))
