"""The ``envconv`` command group and the one place where errors become exit codes.

Library errors (:class:`envconv.errors.EnvconvError`) print one line on stderr and exit 1; click
usage errors exit 2; anything unexpected prints one line and exits 3 (set ``ENVCONV_DEBUG=1``
for the traceback).
"""

from __future__ import annotations

import logging
import os
import sys

import click

from .. import __version__
from ..errors import EnvconvError

__all__ = ["cli", "main"]


class EnvconvGroup(click.Group):
    """A click group that turns exceptions into one-line errors and exit codes."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except EnvconvError as exc:
            click.echo(f"envconv: error: {exc}", err=True)
            ctx.exit(1)
        except (click.exceptions.Exit, click.exceptions.Abort, click.ClickException):
            raise
        except KeyboardInterrupt:
            click.echo("envconv: interrupted", err=True)
            ctx.exit(130)
        except Exception as exc:  # never a traceback for the user
            if os.environ.get("ENVCONV_DEBUG"):
                raise
            message = str(exc).strip().splitlines()
            click.echo(
                f"envconv: internal error: {type(exc).__name__}: {message[0] if message else ''}",
                err=True,
            )
            ctx.exit(3)


@click.group(cls=EnvconvGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="envconv")
@click.option("-v", "--verbose", count=True, help="More log output (-vv for debug).")
def cli(verbose: int) -> None:
    """Convert HDR environment maps between layouts.

    \b
    Example:
      envconv convert sky.exr sky_cross.exr --to cube-vcross --size 512
    """
    level = logging.WARNING - 10 * min(verbose, 2)
    logging.basicConfig(level=level, format="envconv: %(levelname)s: %(message)s")


def main() -> None:
    """Console-script entry point."""
    from . import convert, info, layouts  # noqa: F401  (registers the commands)

    cli.main(prog_name="envconv", standalone_mode=True)


if __name__ == "__main__":  # pragma: no cover
    main()
    sys.exit(0)
