"""One exception tree for everything pneunet reports to a user.

Every error says *what* went wrong and *where* (file:line:column, node or element
name, or simulation time) and, where it helps, *what to try*.  The CLI turns a
:class:`PneunetError` into a message and an exit code; nothing else escapes.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

#: control characters a terminal would act on (ESC, NUL, CR, ...), not tab and line feed
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def printable(text: str) -> str:
    """``text`` with each control character written as Python writes it (``\\x1b``,
    ``\\r``), so that a name or file name never acts on the user's terminal."""
    return _CONTROL.sub(lambda m: repr(m.group())[1:-1], text)


@dataclass(frozen=True)
class SourceSpan:
    """A position in a netlist file (1-based line and column)."""

    file: str
    line: int
    column: int
    text: str = ""  # the offending source line, for the caret display
    via: tuple = ()  # the .include lines ("top.pn:3") through which the file was read

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"

    def caret(self, width: int = 120) -> str:
        """The source line (a window of ``width`` characters around a long line's column)
        with a caret under the column, or '' without text."""
        if not self.text:
            return ""
        text = self.text.rstrip()
        column = len(printable(text[:self.column - 1])) + 1
        text = printable(text)
        if len(text) > width:
            start = max(0, min(column - 1 - width // 2, len(text) - width))
            text = ("…" if start else "") + text[start:start + width] + \
                ("…" if start + width < len(text) else "")
            column = column - start + (1 if start else 0)
        return f"    {text}\n    {' ' * (column - 1)}^"


class PneunetError(Exception):
    """Base of all errors pneunet raises on purpose.

    ``where`` names the place (element, node, file position or time); ``hint``
    says what to try.  ``str(err)`` gives the full one-line message, and
    :meth:`report` a multi-line one with the caret display for netlist errors.
    """

    exit_code = 2

    def __init__(self, message: str, *, where: str | None = None, hint: str | None = None,
                 span: SourceSpan | None = None):
        self.message = message
        self.where = where if where is not None else (str(span) if span else None)
        self.hint = hint
        self.span = span
        super().__init__(self._one_line())

    def _one_line(self) -> str:
        text = f"{self.where}: {self.message}" if self.where else self.message
        if self.hint:
            text += f" (hint: {self.hint})"
        return text

    def report(self) -> str:
        """Multi-line text for a terminal: message, caret display, hint."""
        return _report("error", self.where, self.message, self.span, self.hint)


def _report(kind, where, message, span, hint) -> str:
    lines = [f"{where}: {kind}: {message}" if where else f"{kind}: {message}"]
    if span is not None and span.caret():
        lines.append(span.caret())
    for via in span.via if span is not None else ():
        lines.append(f"  included from {via}")
    if hint:
        lines.append(f"hint: {hint}")
    return printable("\n".join(lines))


class InputWarning(UserWarning):
    """Input that is allowed but probably not what was meant (a bare number far outside a
    parameter's usual range, a scale factor read as a unit): the run goes on; the CLI prints
    ``file:line:column: warning: …`` with the caret line and a hint (``-q`` silences it)."""

    def __init__(self, message: str, *, span: SourceSpan | None = None,
                 where: str | None = None, hint: str | None = None):
        self.message, self.span, self.hint = message, span, hint
        self.where = where if where is not None else (str(span) if span else None)
        text = f"{self.where}: {message}" if self.where else message
        super().__init__(text + (f" (hint: {hint})" if hint else ""))

    def report(self) -> str:
        """Multi-line text for a terminal, like :meth:`PneunetError.report`."""
        return _report("warning", self.where, self.message, self.span, self.hint)


class NetlistError(PneunetError):
    """Malformed netlist text: syntax, units, unknown names, bad includes."""


class TopologyError(PneunetError):
    """A circuit whose graph cannot be simulated (floating or unknown nodes...)."""


class ParameterError(PneunetError):
    """A parameter value outside its valid range or of the wrong dimension."""


class DataError(PneunetError):
    """Measured data that cannot be used as given (missing columns, NaNs...)."""


class SolverError(PneunetError):
    """A simulation that could not be completed (exit code 2, like any input the simulator
    cannot do: the message names the time reached); carries the time reached."""

    def __init__(self, message: str, *, time: float | None = None, partial=None, **kwargs):
        self.time = time
        self.partial = partial  # the Solution up to the failure, if any
        super().__init__(message, **kwargs)
