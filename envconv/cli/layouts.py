"""``envconv layouts``: list the layouts."""

from __future__ import annotations

import click

from .main import cli

__all__ = ["layouts_command"]


@cli.command("layouts")
def layouts_command():
    """List every layout with a one-line description.

    \b
    Example:
      envconv layouts
    """
    from ..layouts import LAYOUTS

    width = max(len(name) for name in LAYOUTS)
    for name, layout in LAYOUTS.items():
        click.echo(f"{name:<{width}}  {layout.description}")
