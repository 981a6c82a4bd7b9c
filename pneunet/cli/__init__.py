"""The ``pneunet`` command: one sub-command per module in this package.

Each sub-command module defines ``register(subparsers)``, which adds its parser
and sets ``func(args) -> int`` as default.  Errors derived from
:class:`~pneunet.errors.PneunetError` become a message and an exit code
(0 ok, 1 every point of a sweep failed, 2 bad input or a simulation that cannot
be completed); no traceback reaches the user.
"""
from __future__ import annotations

import argparse
import importlib
import sys
import warnings

#: sub-command modules, in the order ``pneunet --help`` lists them
SUBCOMMAND_MODULES = ("run", "check", "fit", "diagnose", "sweep", "branches", "fit_trace",
                       "design", "piping")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pneunet",
        description="Simulate pneumatic circuits of fluid-driven membrane valves, "
                    "identify valve parameters from measurements and diagnose the model.",
        epilog="exit codes: 0 ok, 2 bad input or a simulation that cannot be completed "
               "(sweep: 1 if every point failed). "
               "Run 'pneunet COMMAND --help' for a command's options.")
    from .. import __version__
    parser.add_argument("--version", action="version", version=f"pneunet {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMAND_MODULES:
        try:
            module = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name == f"{__name__}.{name}":
                continue  # sub-command not part of this build
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    from ..errors import PneunetError

    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        with warnings.catch_warnings():
            _show_solver_warnings(quiet=getattr(args, "quiet", False))
            return int(args.func(args) or 0)
    except PneunetError as err:
        print(err.report(), file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def _show_solver_warnings(quiet: bool) -> None:
    """The integrator's warnings as ``warning: …`` lines on stderr; none with -q."""
    from ..engine.diagnostics import SolverWarning

    if quiet:
        warnings.simplefilter("ignore", SolverWarning)
        return
    default = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, SolverWarning):
            print(f"warning: {message}", file=sys.stderr)
        else:
            default(message, category, filename, lineno, file, line)
    warnings.showwarning = show


if __name__ == "__main__":
    sys.exit(main())
