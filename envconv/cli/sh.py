"""``envconv sh INPUT``: the order-2 spherical harmonics of an environment, as JSON."""

from __future__ import annotations

import json

import click

from .main import cli
from .messages import echo_result
from .options import layout_choice

__all__ = ["sh_command"]


@cli.command("sh")
@click.argument("input_path", metavar="INPUT")
@click.option("--from", "from_", type=layout_choice(), help="Input layout (default: detect).")
@click.option("--frame", type=click.Choice(["world", "cube"]), default="world", show_default=True,
              help="Evaluate the basis in envconv's world frame or the DDS/KTX2 cube frame "
              "(x negated).")  # fmt: skip
def sh_command(input_path, from_, frame):
    """Print the 9 RGB coefficients of INPUT's order-2 SH projection and its irradiance.

    JSON with the basis order and normalisation (Ramamoorthi & Hanrahan 2001: real,
    orthonormal; l=0, l=1 as y z x, l=2 as xy yz 3z²-1 xz x²-y²), the radiance coefficients
    L_lm per channel, the irradiance coefficients E_lm and R&H's 4x4 matrices M. See
    docs/ibl.md.

    \b
    Example:
      envconv sh sky.exr > sky_sh.json
    """
    from ..io import read
    from ..resample.harmonics import sh_record

    echo_result(json.dumps(sh_record(read(input_path, layout=from_), frame), indent=2))
