"""Solver diagnostics: what SUNDIALS prints, captured and turned into pneunet warnings.

SUNDIALS writes from C: warnings through its logger to the process's stdout
(``[WARNING][rank 0][<build path>/ida_ls.c:1687][idaLsPerf] Warning: at t = …``), and
errors through scikit-sundae's handler, a Python ``print`` on ``sys.stdout``
(``[IDAHandleFailure, Error: -4] At t = …``); scikits.odes prints ``[IDA ERROR]  IDASolve``
and the message on the next line.

:func:`captured` wraps a whole solve (never a step): while it runs, file
descriptors 1 and 2 go to temporary files and ``sys.stdout``/``sys.stderr`` to
buffers (tens of µs per solve; simulations in several threads of one process take
turns).  Afterwards the SUNDIALS lines become
:class:`SolverMessage` s, counted in the solution's ``stats`` (``solver_messages``,
``solver_diagnostics``) or attached to the :class:`~pneunet.common.errors.SolverError`
(``err.diagnostics``), and announced once per kind and process as a
:class:`SolverWarning`; any other output is written back where it was going.
"""
from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import functools
import io
import os
import re
import sys
import tempfile
import threading
import warnings
from dataclasses import dataclass

from .errors import SolverError


class SolverWarning(UserWarning):
    """A message of the integrator about a simulation (see :class:`Diagnostics`)."""


@dataclass(frozen=True)
class SolverMessage:
    """One SUNDIALS message: ``kind`` (the reporting function, and the error code for
    errors: ``'idaLsPerf'``, ``'IDAHandleFailure -4'``), simulated ``time`` (s, None when
    the message gives none) and its ``text`` without build paths."""

    kind: str
    time: float | None
    text: str


#: what a kind of message means for the result, by reporting function or error code
MEANINGS = {
    "idaLsPerf": "the iterative linear solver needed many iterations: slower, not less accurate",
    "-1": "too many steps before the next output time",
    "-3": "the local error test failed repeatedly (a very fast change or a discontinuity)",
    "-4": "Newton's corrector did not converge repeatedly (a sharp corner or a stiff switch)",
    "-6": "the Jacobian set-up failed",
    "-7": "the linear solve failed",
    "-8": "the circuit equations could not be evaluated",
    "-11": "a pressure would have become negative",
    "-22": "too many steps before the next output time",
}

_WARNING = re.compile(r"^\[(WARNING|ERROR)\]\[rank \d+\]\[[^\]]*\]\[(\w+)\]\s*(.*)$")
_HANDLER = re.compile(r"^\[(\w+), Error: (-?\d+)\]\s*(.*)$")
_LEGACY = re.compile(r"^\[IDA (?:ERROR|WARNING)\]\s+(\w+)$")
_TIME = re.compile(r"\bat t = ([-+]?[0-9.]+(?:[eE][-+]?\d+)?)", re.IGNORECASE)


def parse(text: str) -> tuple[list[SolverMessage], str]:
    """The SUNDIALS messages in ``text``, and the rest of it (blank lines around
    messages dropped)."""
    found, rest = [], []
    lines = text.splitlines(keepends=True)
    while lines:
        line = lines.pop(0)
        bare = line.strip()
        warning, handler, legacy = (_WARNING.match(bare), _HANDLER.match(bare),
                                    _LEGACY.match(bare))
        if warning:
            kind = warning.group(2)
            body = re.sub(r"^Warning:\s*", "", warning.group(3))
        elif handler:
            kind, body = f"{handler.group(1)} {handler.group(2)}", handler.group(3)
        elif legacy:  # scikits.odes: the message on the indented lines that follow
            kind, body = legacy.group(1), ""
            while lines and lines[0].startswith("  "):
                body += " " + lines.pop(0).strip()
            body = body.strip()
        else:
            rest.append(line)
            continue
        time = _TIME.search(body)
        found.append(SolverMessage(kind, float(time.group(1)) if time else None, body))
    if found:
        rest = [line for line in rest if line.strip()]
    return found, "".join(rest)


@dataclass(frozen=True)
class Diagnostics:
    """The integrator's messages during one simulation.

    ``recovered`` is False when the simulation stopped (the result ends early);
    ``where`` names the node the first message points at: for a failure the node whose
    pressure changes fastest where it stopped, else the fastest one around the time
    of the first message.
    """

    messages: tuple = ()
    recovered: bool = True
    where: str | None = None

    def __repr__(self) -> str:
        state = "recovered" if self.recovered else "stopped" + (
            f" near {self.where}" if self.where else "")
        return (f"<Diagnostics: {len(self.messages)} message(s) of {len(self.kinds())} "
                f"kind(s), {state}>")

    def kinds(self) -> dict:
        """{kind: {'count', 'first_t', 'last_t' (s), 'text' (the first message)}}."""
        out = {}
        for m in self.messages:
            entry = out.setdefault(m.kind, {"count": 0, "first_t": m.time, "last_t": m.time,
                                            "text": m.text})
            entry["count"] += 1
            if m.time is not None:
                entry["first_t"] = m.time if entry["first_t"] is None else entry["first_t"]
                entry["last_t"] = m.time
        return out

    def as_data(self) -> dict:
        """JSON-ready summary: count, recovered, where, kinds."""
        return {"count": len(self.messages), "recovered": self.recovered, "where": self.where,
                "kinds": self.kinds()}

    def sentences(self) -> list[str]:
        """One line per kind: what, when, where and what it means for the result."""
        lines = []
        for kind, k in self.kinds().items():
            when = "" if k["first_t"] is None else (
                f" at t = {k['first_t']:.4g} s" if k["count"] == 1 or k["first_t"] == k["last_t"]
                else f" between t = {k['first_t']:.4g} and {k['last_t']:.4g} s")
            meaning = MEANINGS.get(_code(kind, k["text"]), k["text"].rstrip("."))
            verdict = ("the integrator recovered: the result passed its error test" if
                       self.recovered else "the simulation stopped: the result ends there")
            where = f" near {self.where}" if self.where else ""
            times = "" if k["count"] == 1 else f" ({k['count']} times)"
            lines.append(f"IDA {kind}{times}{when}{where}: {meaning}; {verdict}")
        return lines


#: message texts of the bindings that print no error code, and the code they stand for
_TEXT_CODES = (("corrector convergence failed", "-4"), ("error test failed", "-3"),
               ("mxstep", "-1"))


def _code(kind: str, text: str) -> str:
    """The IDA error code of a message kind ('-4'), or its reporting function."""
    code = kind.split()[-1]
    if code in MEANINGS:
        return code
    return next((c for words, c in _TEXT_CODES if words in text), code)


_announced: set = set()  # (kind, recovered) already shown in this process


def announce(diagnostics: Diagnostics) -> None:
    """Warn once per kind and process, for a recovered and for a stopped simulation,
    pointing at the first caller outside pneunet."""
    for kind, sentence in zip(diagnostics.kinds(), diagnostics.sentences()):
        key = (kind, diagnostics.recovered)
        if key not in _announced:
            _announced.add(key)
            warnings.warn(sentence, SolverWarning, stacklevel=_outside_pneunet())


def _outside_pneunet() -> int:
    """The stacklevel of the innermost frame not in the pneunet package."""
    frame, level = sys._getframe(2), 2
    while frame is not None and frame.f_globals.get("__name__", "").startswith("pneunet"):
        frame, level = frame.f_back, level + 1
    return level


# -- capture --------------------------------------------------------------------------
_lock = threading.Lock()
_local = threading.local()
_files: dict = {}  # "pid", "fds": this process's temporary files for fds 1 and 2


class _Capture:
    """Output of this process redirected to temporary files and buffers, once."""

    def __enter__(self):
        if _files.get("pid") != os.getpid():  # a forked worker gets its own files
            _files.update(pid=os.getpid(),
                          fds=(tempfile.TemporaryFile(), tempfile.TemporaryFile()))
        self.files = _files["fds"]
        self.streams = (sys.stdout, sys.stderr)
        for stream in self.streams:
            with contextlib.suppress(Exception):
                stream.flush()
        _libc_flush()
        try:
            self.saved = [os.dup(1), os.dup(2)]
        except OSError:  # a process without fds 1 and 2: C output goes nowhere anyway
            self.saved = []
        for fd, _ in zip((1, 2), self.saved):
            os.dup2(self.files[fd - 1].fileno(), fd)
        self.buffers = (io.StringIO(), io.StringIO())
        sys.stdout, sys.stderr = self.buffers
        self.terminal = None
        return self

    def user_stderr(self):
        """A stream to what stderr reached before the capture (for progress bars)."""
        if self.terminal is None:
            stream = self.streams[1]
            self.terminal = (os.fdopen(os.dup(self.saved[1]), "w", buffering=1)
                             if _fileno(stream) == 2 and self.saved else stream)
        return self.terminal

    def __exit__(self, *exc) -> None:
        sys.stdout, sys.stderr = self.streams
        _libc_flush()
        for fd, saved in zip((1, 2), self.saved):
            os.dup2(saved, fd)
            os.close(saved)
        if self.terminal is not None and self.terminal is not self.streams[1]:
            self.terminal.close()
        self.messages = []
        for file, buffer, stream in zip(self.files, self.buffers, self.streams):
            file.seek(0)
            raw = file.read().decode(errors="replace")
            file.seek(0)
            file.truncate()
            messages, rest = parse(raw + buffer.getvalue())
            self.messages.extend(messages)
            if rest:
                stream.write(rest)
                stream.flush()


def _fileno(stream):
    try:
        return stream.fileno()
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):
        return None


@functools.cache
def _libc():
    return ctypes.CDLL(None)


def _libc_flush():
    """Flush C stdio buffers (SUNDIALS' logger writes through them)."""
    _libc().fflush(None)


def user_stderr():
    """Where a progress bar should draw: the user's stderr, also during a capture."""
    capture = getattr(_local, "capture", None)
    return capture.user_stderr() if capture is not None else sys.stderr


def captured(solve):
    """Decorate a function that runs the integrator and returns a Solution (see module)."""

    @functools.wraps(solve)
    def wrapper(*args, **kwargs):
        if getattr(_local, "capture", None) is not None:
            return solve(*args, **kwargs)  # an outer call captures
        with _lock:
            with _Capture() as capture:
                _local.capture = capture
                try:
                    result, failure = solve(*args, **kwargs), None
                except SolverError as err:
                    result, failure = None, err
                finally:
                    _local.capture = None
        found = Diagnostics(tuple(capture.messages), failure is None,
                            failure.where if failure is not None else
                            _fastest_node(result, capture.messages))
        if found.messages:
            announce(found)
        for listener in _listeners:
            listener.append(found)
        if failure is not None:
            failure.diagnostics = found
            raise failure
        return dataclasses.replace(result, stats=dict(
            result.stats, solver_messages=len(found.messages),
            **({"solver_diagnostics": found.as_data()} if found.messages else {})))
    return wrapper


_listeners: list[list] = []


def _fastest_node(solution, messages) -> str | None:
    """'node X': the unknown whose pressure changes fastest (kPa/s) around the time of
    the first message that gives one; None without such a message."""
    import numpy as np

    times = [m.time for m in messages if m.time is not None]
    t = solution.t
    if not times or t.size < 3:
        return None
    j = int(np.searchsorted(t, times[0]))
    lo, hi = max(j - 2, 0), min(j + 2, t.size - 1)
    span = max(t[hi] - t[lo], 1e-12)
    rates = {k: abs(solution[k][hi] - solution[k][lo]) / span for k in solution.signals
             if k.startswith("p_") and solution.units[k] == "kPa"}
    return f"node {max(rates, key=rates.get)[2:]}" if rates else None


class _Relayed:
    """``fun`` for a worker process: returns its value and its simulations' Diagnostics."""

    def __init__(self, fun):
        self.fun = fun

    def __call__(self, x):
        with collect() as heard:
            value = self.fun(x)
        return value, heard


def pool_map(pool, fun, xs) -> list:
    """``list(pool.map(fun, xs))``, passing the workers' Diagnostics on to the
    :func:`collect` blocks of this process (the workers announce their own warnings)."""
    out = []
    for value, heard in pool.map(_Relayed(fun), xs):
        for listener in _listeners:
            listener.extend(heard)
        out.append(value)
    return out


def summarize(heard: list[Diagnostics]) -> dict:
    """JSON-ready totals over simulations: messages, simulations with messages, stopped
    simulations, and messages by kind."""
    kinds: dict[str, int] = {}
    for diagnostics in heard:
        for kind, entry in diagnostics.kinds().items():
            kinds[kind] = kinds.get(kind, 0) + entry["count"]
    return {"count": sum(kinds.values()), "simulations": len(heard),
            "with_messages": sum(bool(d.messages) for d in heard),
            "stopped": sum(not d.recovered for d in heard), "kinds": kinds}


@contextlib.contextmanager
def collect():
    """Gather the :class:`Diagnostics` of every simulation run inside the block (a list)."""
    heard: list[Diagnostics] = []
    _listeners.append(heard)
    try:
        yield heard
    finally:
        _listeners.remove(heard)
