"""``envconv layouts``: list the layouts."""

from __future__ import annotations

import click

from .main import cli

__all__ = ["layouts_command"]


@cli.command("layouts")
def layouts_command():
    """List every layout with a one-line description, then the skybox face sets.

    A face set is how a game or engine names and turns the six files of a cube-faces map
    (--in-convention / --out-convention NAME; draw one with
    envconv pattern 'sky_{face}.png' --to cube-faces --out-convention NAME).

    \b
    Example:
      envconv layouts
    """
    from ..layouts import ALIASES, LAYOUTS
    from ..layouts.facesets import FACE_SETS

    width = max(len(name) for name in LAYOUTS)
    for name, layout in LAYOUTS.items():
        aliases = [alias for alias, target in ALIASES.items() if target == name]
        also = f" (also {', '.join(aliases)})" if aliases else ""
        click.echo(f"{name:<{width}}  {layout.description}{also}")
    click.echo("")
    click.echo("face sets of cube-faces (--in-convention / --out-convention NAME):")
    width = max(len(name) for name in FACE_SETS)
    files = {name: " ".join(s.order()) for name, s in FACE_SETS.items()}
    fwidth = max(len(text) for text in files.values())
    for name, face_set in FACE_SETS.items():
        also = f" (also {', '.join(face_set.aliases)})" if face_set.aliases else ""
        click.echo(f"{name:<{width}}  {files[name]:<{fwidth}}  {face_set.tool}{also}")
