"""The ``pneunet`` command: one sub-command per module in this package.

Each sub-command module defines ``register(subparsers)``, which adds its parser
and sets ``func(args) -> int`` as default.  Errors derived from
:class:`~pneunet.common.errors.PneunetError` become a message and an exit code
(0 ok, 1 every point of a sweep failed, 2 bad input, an unwritable output or a
simulation that cannot be completed); a closed pipe (``| head``) ends quietly with 0; no
traceback reaches the user.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib
import sys
import warnings

#: sub-command modules, in the order ``pneunet --help`` lists them
SUBCOMMAND_MODULES = ("run", "check", "draw", "fit", "diagnose", "sweep", "branches",
                       "fit_trace", "design", "piping")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every sub-command, or of ``command`` alone when it names one (a run
    then imports only its own module: ``pneunet run`` never loads the fitting code)."""
    by_command = {name.replace("_", "-"): name for name in SUBCOMMAND_MODULES}
    names = [by_command[command]] if command in by_command else SUBCOMMAND_MODULES
    parser = argparse.ArgumentParser(
        prog="pneunet",
        description="Simulate pneumatic circuits of fluid-driven membrane valves, "
                    "identify valve parameters from measurements and diagnose the model.",
        epilog="exit codes: 0 ok, 2 bad input or a simulation that cannot be completed "
               "(sweep: 1 if every point failed). "
               "Run 'pneunet COMMAND --help' for a command's options.")
    from ... import __version__
    parser.add_argument("--version", action="version", version=f"pneunet {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in names:
        try:
            module = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name == f"{__name__}.{name}":
                continue  # sub-command not part of this build
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    from ...common.errors import PneunetError, printable

    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv[0] if argv else None)
    try:
        with _wrapped("stderr", _PrintableStderr):  # argparse quotes the user's text in its errors
            args = parser.parse_args(argv)
    except SystemExit as done:  # --help, --version, or a bad option (argparse said why)
        return done.code if isinstance(done.code, int) else 2
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        with warnings.catch_warnings(), _wrapped("stdout", _NamedStdout):
            _show_solver_warnings(quiet=getattr(args, "quiet", False))
            code = int(args.func(args) or 0)
            sys.stdout.flush()  # a full disk or a closed pipe is reported here, not at exit
        return code
    except PneunetError as err:
        print(err.report(), file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return _closed_pipe()
    except OSError as err:  # writing a result: a full disk, /dev/full, a vanished folder
        print(printable(f"error: {_written(err)}: {err.strerror or err}"), file=sys.stderr)
        return 2
    except MemoryError:
        print("error: out of memory (a size beyond what this machine holds); "
              "hint: ask for fewer points, samples or elements", file=sys.stderr)
        return 2


def _written(err: OSError) -> str:
    """The file an OSError was about: its name, else the file object being written in the
    innermost frame that holds one (a write error carries no name)."""
    import io

    if err.filename is not None:
        return str(err.filename)
    tb, names = err.__traceback__, []
    while tb is not None:
        names += [v.name for v in tb.tb_frame.f_locals.values()
                  if isinstance(v, io.IOBase) and isinstance(getattr(v, "name", None), str)]
        tb = tb.tb_next
    return names[-1] if names else "an output file"


class _NamedStdout:
    """sys.stdout whose write errors name it (``OSError.filename`` "standard output") and
    whose control characters are escaped (a name never acts on the terminal)."""

    def __init__(self, stream):
        self._stream = stream

    def __getattr__(self, name):
        return getattr(self._stream, name)

    def write(self, text):
        from ...common.errors import printable

        return self._call(self._stream.write, printable(text) if isinstance(text, str) else text)

    def flush(self):
        return self._call(self._stream.flush)

    def _call(self, method, *args):
        try:
            return method(*args)
        except BrokenPipeError:
            raise
        except OSError as err:
            _drop_stdout()
            raise OSError(err.errno, err.strerror, "standard output") from None


class _PrintableStderr:
    """sys.stderr with control characters escaped (for argparse's messages)."""

    def __init__(self, stream):
        self._stream = stream

    def __getattr__(self, name):
        return getattr(self._stream, name)

    def write(self, text):
        from ...common.errors import printable

        return self._stream.write(printable(text))


@contextlib.contextmanager
def _wrapped(name: str, wrapper):
    """``sys.<name>`` replaced by ``wrapper(sys.<name>)`` while active."""
    stream = getattr(sys, name)
    setattr(sys, name, wrapper(stream))
    try:
        yield
    finally:
        setattr(sys, name, stream)


def _closed_pipe() -> int:
    """The reader of stdout went away (``| head``): it took what it wanted, so stop
    quietly with exit 0 (not the shell's 141 of a tool killed by SIGPIPE)."""
    _drop_stdout()
    return 0


def _drop_stdout() -> None:
    """Point stdout at /dev/null, so that Python's flush at exit writes nothing."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


def _show_solver_warnings(quiet: bool) -> None:
    """The integrator's warnings as ``warning: …`` lines on stderr; none with -q."""
    from ...common.solver_messages import SolverWarning
    from ...common.errors import InputWarning, printable

    if quiet:
        warnings.simplefilter("ignore", SolverWarning)
        warnings.simplefilter("ignore", InputWarning)
        return
    default = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if isinstance(message, InputWarning):
            print(message.report(), file=sys.stderr)
        elif issubclass(category, SolverWarning):
            print(printable(f"warning: {message}"), file=sys.stderr)
        else:
            default(message, category, filename, lineno, file, line)
    warnings.showwarning = show


if __name__ == "__main__":
    sys.exit(main())
