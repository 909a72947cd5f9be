"""The ``envconv`` command group and the one place where errors become exit codes.

``envconv`` is a chained group: ``envconv read IN resample … write OUT resample … write OUT2``.
Each command of a chain parses its own arguments up to the next command name (options may
follow positional arguments, as in ``write out.exr --bit-depth half``); the result callback
composes the steps (:mod:`envconv.cli.compose`). ``convert``, ``info``, ``layouts`` and ``run``
are whole commands that cannot be chained with others.

Exit statuses: 0 success; 2 bad usage (click's usage errors and envconv's own
:class:`envconv.errors.UsageError`); 1 a run-time failure (any other
:class:`envconv.errors.EnvconvError`: a missing or damaged file, a layout that does not fit);
3 an internal error, a bug in envconv (one line naming the exception; set ``ENVCONV_DEBUG=1``
for the traceback); 130 or 143 when SIGINT or SIGTERM ends a run (:mod:`envconv.engine.interrupt`). Running out of memory is a run-time failure (1). Each
error is one line on stderr; stdout carries results only.
"""

from __future__ import annotations

import logging
import os
import sys

import click

from .. import __version__
from ..errors import EnvconvError, UsageError
from ..limits import MAX_THREADS
from .messages import did_you_mean, one_line, stdout_failed, step_typo

__all__ = ["cli", "main", "EnvconvCommand", "COMMANDS"]

#: Every command, and the module under envconv.cli that defines it. A module is imported when
#: one of its commands is used (or help lists them all), so ``convert`` does not import the
#: batch, graph and pattern machinery. tests/test_cli_chain.py checks this table.
COMMANDS = {
    "batch": "batch", "colorspace": "chain", "convert": "convert", "exposure": "chain",
    "info": "info", "layouts": "layouts", "pattern": "pattern", "preview": "preview", "read": "chain",
    "resample": "chain", "rotate": "chain", "run": "run", "sh": "sh", "view": "view",
    "write": "chain",
}  # fmt: skip
#: Commands that run on their own and cannot be chained with others.
STANDALONE = {"convert", "info", "layouts", "run", "pattern", "preview", "sh", "view"}


def _load_commands(names=None) -> None:
    """Import the modules that define ``names`` (default: every command)."""
    import importlib

    for module in sorted(
        {COMMANDS[n] for n in (COMMANDS if names is None else names) if n in COMMANDS}
    ):
        importlib.import_module(f"{__package__}.{module}")


def _split_chain(command: click.Command, names: set[str], args: list[str]):
    """Split ``args`` at the first command name that is not an option's value."""
    takes_value = {}
    for param in command.params:
        if isinstance(param, click.Option) and not param.is_flag and not param.count:
            for opt in (*param.opts, *param.secondary_opts):
                takes_value[opt] = (param.nargs, getattr(param, "_flag_needs_value", False))
    index, options_done = 0, False
    while index < len(args):
        token = args[index]
        if token in names:
            break
        index += 1
        if options_done or not token.startswith("-") or len(token) < 2:
            continue
        if token == "--":
            options_done = True
            continue
        name = token.split("=", 1)[0] if token.startswith("--") else token[:2]
        attached = "=" in token if token.startswith("--") else len(token) > 2
        if name in takes_value and not attached:
            nargs, optional = takes_value[name]
            if optional and (index >= len(args) or args[index] in names):
                continue
            index += nargs
    return args[:index], args[index:]


class EnvconvCommand(click.Command):
    """A command that can sit in a chain: its arguments end at the next command name."""

    def make_context(self, info_name, args, parent=None, **extra):
        group = parent.command if parent is not None else None
        if isinstance(group, click.Group) and group.chain:
            names = group.list_commands(parent)
            head, tail = _split_chain(self, set(names), list(args))
            extra.update(allow_extra_args=False, allow_interspersed_args=True)
            try:
                ctx = super().make_context(info_name, list(head), parent=parent, **extra)
            except click.UsageError:  # `read x.exr resampel --to …`: say so, not "no such option"
                typo = step_typo(head, names)
                if typo is None:
                    raise
                raise click.UsageError(f"no such command '{typo}'{did_you_mean(typo, names)}",
                                       ctx=parent) from None  # fmt: skip
            ctx.args = tail
            return ctx
        return super().make_context(info_name, args, parent=parent, **extra)


class EnvconvGroup(click.Group):
    """A click group that turns exceptions into one-line errors and exit codes."""

    command_class = EnvconvCommand

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        """Run the group; in standalone mode a usage error is one line on stderr, exit 2."""
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            result = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.exceptions.NoArgsIsHelpError as exc:
            exc.show()
            sys.exit(exc.exit_code)
        except click.ClickException as exc:
            message = one_line(exc.format_message() or type(exc).__name__)
            ctx = getattr(exc, "ctx", None)
            hint = f" (see '{ctx.command_path} --help')" if ctx is not None else ""
            click.echo(f"envconv: error: {message}{hint}", err=True)
            sys.exit(exc.exit_code)
        except click.exceptions.Abort as exc:
            if isinstance(exc.__cause__, KeyboardInterrupt):  # a signal while click parsed
                _interrupted(exc.__cause__)
            click.echo("envconv: aborted", err=True)
            sys.exit(1)
        except OSError as exc:  # click's own --help or --version on a stdout that takes nothing
            _say(f"envconv: error: {stdout_failed(exc)}")
            sys.exit(1)
        sys.exit(result if isinstance(result, int) else 0)

    def list_commands(self, ctx):
        return sorted(COMMANDS)

    def get_command(self, ctx, cmd_name):
        _load_commands([cmd_name])
        return super().get_command(ctx, cmd_name)

    def resolve_command(self, ctx, args):
        try:
            name, command, rest = super().resolve_command(ctx, args)
        except click.UsageError as exc:
            hint = did_you_mean(args[0], COMMANDS) if args and args[0] not in COMMANDS else ""
            if not hint:
                raise
            raise click.UsageError(f"no such command '{args[0]}'{hint}", ctx=ctx) from exc
        if self.chain and command is not None:
            chain = ctx.meta.setdefault("envconv.chain", [])
            chain.append(name)
            alone = [n for n in chain if n in STANDALONE]
            if alone and len(chain) > 1:
                raise click.UsageError(
                    f"'{alone[0]}' runs on its own; it cannot be chained with other "
                    f"commands (found: {' '.join(chain)})",
                    ctx=ctx,
                )
        return name, command, rest

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except EnvconvError as exc:
            click.echo(f"envconv: error: {one_line(str(exc))}", err=True)
            ctx.exit(2 if isinstance(exc, UsageError) else 1)
        except (click.exceptions.Exit, click.exceptions.Abort, click.ClickException):
            raise
        except BrokenPipeError:  # `envconv layouts | head`: click exits quietly
            raise
        except KeyboardInterrupt as exc:  # SIGINT or SIGTERM (envconv.engine.interrupt): 130 or 143
            _interrupted(exc)
        except MemoryError as exc:  # not a bug: the machine is too small for this run
            detail = one_line(str(exc)) if str(exc).strip() else ""
            click.echo(f"envconv: error: out of memory{': ' + detail if detail else ''}", err=True)
            ctx.exit(1)
        except Exception as exc:  # never a traceback for the user
            if os.environ.get("ENVCONV_DEBUG"):
                raise
            message = str(exc).strip().splitlines()
            click.echo(
                f"envconv: internal error: {type(exc).__name__}: {message[0] if message else ''}",
                err=True,
            )
            ctx.exit(3)


@click.group(cls=EnvconvGroup, chain=True, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="envconv")
@click.option("-v", "--verbose", count=True, help="More log output (-vv for debug).")
@click.option(
    "--threads",
    type=click.IntRange(1, MAX_THREADS),
    default=None,
    metavar="N",
    help="Threads for resampling (default: ENVCONV_THREADS, else one per core).",
)
def cli(verbose: int, threads: int | None) -> None:
    """Convert HDR environment maps between layouts.

    \b
    Examples:
      envconv convert sky.exr sky_cross.exr --to cube-vcross --size 512
      envconv read sky.exr resample --to cube-vcross --size 512 write cross.exr \\
              resample --to paraboloid --size 256 --alpha --guard 2 write para.exr

    Chained steps: read, rotate, exposure, colorspace, resample, write. Each resample starts
    from the source (the last read and the steps that follow it), never from another output.
    Before any work a run is refused if an output is an input (also through a link) or two
    outputs share a path, and with -n (convert, write, run, batch) if an output exists;
    otherwise outputs are replaced atomically (docs/shell.md).
    Options of envconv itself (-v, --threads) come before the command:
    envconv --threads 1 convert ...
    """
    level = logging.WARNING - 10 * min(verbose, 2)
    for number in (logging.DEBUG, logging.INFO, logging.WARNING, logging.ERROR):
        # "envconv: warning: …" whether a message comes from the library's log or the CLI.
        logging.addLevelName(number, logging.getLevelName(number).lower())
    logging.basicConfig(level=level, format="envconv: %(levelname)s: %(message)s")
    from ..io.chatter import capture_descriptors

    # This process is the command line's: what the image libraries print may be captured
    # (folded into errors, kept off stdout) for the command's length (envconv.io.chatter).
    previous = capture_descriptors(True)
    click.get_current_context().call_on_close(lambda: capture_descriptors(previous))
    if threads is not None:
        from ..resample.kernels import set_threads

        # Restored when the command ends: a command run in a library's process (click's
        # runner, a test) leaves the process's count as it found it.
        previous_threads = set_threads(threads)
        click.get_current_context().call_on_close(lambda: set_threads(previous_threads))


def _say(line: str) -> None:
    """``line`` on stderr, if stderr takes it."""
    try:
        click.echo(line, err=True)
    except OSError:
        pass


def _interrupted(exc: BaseException) -> None:
    from ..engine.interrupt import describe, done, exit_status, remove_live_temps

    remove_live_temps()  # a temp made just before the signal, not yet in its writer's hands
    if done():  # not yet reported by the watchdog (envconv.engine.interrupt)
        click.echo(f"envconv: error: {describe(exc)}", err=True)
    sys.exit(exit_status(exc))


#: numpy's OpenBLAS starts one thread per core when numpy is imported, and joins them when the
#: process exits. envconv does no linear algebra beyond 3 × 3 matrices (OpenBLAS runs those on
#: the calling thread anyway), so the command line asks OpenBLAS, through its documented
#: variable and before numpy loads, for no pool: a one-shot conversion then ends about 15 ms
#: sooner, and no idle BLAS thread competes with the native core's threads. A value set by
#: the user is kept; a library import of envconv changes nothing.
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "1")


def main() -> None:
    """Console-script entry point (reached through :mod:`envconv.__main__`, which installs
    the signal handlers before this module loads)."""
    from ..engine.interrupt import closing, install

    try:
        install()  # once: already done when started as the console script
        os.environ.setdefault(*BLAS_THREADS)
        import warnings

        from .messages import show_warning

        warnings.showwarning = show_warning  # a Python warning is one line too
        cli.main(prog_name="envconv", standalone_mode=True)
    except KeyboardInterrupt as exc:  # before or after a command ran
        _interrupted(exc)
    finally:
        closing()  # the run is over: a late signal no longer breaks the interpreter's ending


if __name__ == "__main__":  # pragma: no cover
    main()
