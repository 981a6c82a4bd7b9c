"""Safe evaluation of ``{expressions}`` and ``.param`` values (never Python ``eval``).

Expressions are parsed with the ``expr`` rule of ``grammar.lark`` and walked here.
They work on plain numbers: a parameter defined with a unit (``.param V=200mL``)
holds its value in pneunet's internal unit (mL), so ``{2*V}`` is 400 mL where a
volume is expected.

Supported: ``+ - * / % ** ^``, comparisons ``< <= > >= == !=``, ``&& || !``,
``c ? a : b``, constants ``pi``, and the functions in :data:`FUNCTIONS`.
Numbers may carry a SPICE scale suffix (``2k``, ``5m``) or a single-word unit
(``200mL``, ``5ms``), converted to the internal unit of its dimension.
"""
from __future__ import annotations

import dataclasses
import functools
import math

from ..common.errors import NetlistError, SourceSpan
from .values import number_in_expression, split


def _if(c, a, b):
    return a if c else b


FUNCTIONS = {
    "sqrt": math.sqrt, "exp": math.exp, "log": math.log, "ln": math.log, "log10": math.log10,
    "sin": math.sin, "cos": math.cos, "tan": math.tan, "asin": math.asin, "acos": math.acos,
    "atan": math.atan, "atan2": math.atan2, "sinh": math.sinh, "cosh": math.cosh,
    "tanh": math.tanh, "abs": abs, "min": min, "max": max, "pow": math.pow,
    "floor": math.floor, "ceil": math.ceil, "round": round, "hypot": math.hypot,
    "if": _if, "sgn": lambda x: (x > 0) - (x < 0), "int": lambda x: float(int(x)),
}
CONSTANTS = {"pi": math.pi}


class Scope:
    """Parameter values visible to an expression (a chain of dicts)."""

    def __init__(self, values=None, parent: "Scope | None" = None):
        self.values = dict(values or {})
        self.parent = parent

    def lookup(self, name):
        scope = self
        while scope is not None:
            if name in scope.values:
                return scope.values[name]
            scope = scope.parent
        return None

    def names(self):
        out, scope = set(), self
        while scope is not None:
            out.update(scope.values)
            scope = scope.parent
        return out

    def child(self, values=None) -> "Scope":
        return Scope(values, self)


def _shift(span: SourceSpan, meta_column: int, base_column: int) -> SourceSpan:
    return dataclasses.replace(span, column=base_column + meta_column - 1)


def evaluate(text: str, scope: Scope, span: SourceSpan, column: int | None = None,
             limits=None) -> float:
    """Evaluate expression ``text`` whose first character is at ``column`` of ``span``'s line
    (nested at most ``limits.max_expression_depth`` deep)."""
    from lark.exceptions import UnexpectedInput

    from .limits import DEFAULT

    base = span.column if column is None else column
    if not text.strip():
        raise NetlistError("empty expression {}", span=_shift(span, 1, base))
    try:
        tree = _parse(text)
        value = _Evaluator(scope, span, base, limits or DEFAULT).eval(tree)
    except RecursionError:
        raise NetlistError("expression nested too deeply (more levels than Python's "
                           "recursion limit)", span=_shift(span, 1, base),
                           hint="split it into .param steps") from None
    except UnexpectedInput as err:
        col = getattr(err, "column", 1)
        tok = getattr(err, "token", None)
        if col is None or col < 1 or (tok is not None and tok.type == "$END"):
            col = len(text) + 1
        what = "end of expression" if tok is not None and tok.type == "$END" else \
            f"{_cut(tok.value)!r}" if tok is not None else repr(text[col - 1:col] or "end")
        raise NetlistError(f"syntax error in expression {{{_cut(text)}}}: unexpected {what}",
                           span=_shift(span, col, base)) from None
    if not math.isfinite(value):
        raise NetlistError(f"expression gives {value} (a result or a step overflows)",
                           span=_shift(span, 1, base), hint="check the exponents and the "
                           "parameter values it uses")
    return value


def check_names(text: str, known, span: SourceSpan, column: int, hint: str) -> None:
    """A located NetlistError (did you mean …?) for the first name in expression ``text``
    that is neither in ``known`` nor a constant, or an unknown function, before anything
    is evaluated; a syntax error is reported as :func:`evaluate` does."""
    from lark import Token
    from lark.exceptions import UnexpectedInput

    try:
        tree = _parse(text)
    except UnexpectedInput:
        evaluate(text, Scope(), span, column)  # raises the located syntax error
        raise  # pragma: no cover
    if isinstance(tree, Token):
        tokens = [tree]
    else:
        calls = list(tree.find_data("func"))
        for call in calls:
            if str(call.children[0]).lower() not in FUNCTIONS:
                _Evaluator(Scope(), span, column, None).r_func(call)  # raises: unknown
        functions = {id(f.children[0]) for f in calls}
        tokens = [t for t in tree.scan_values(lambda v: isinstance(v, Token))
                  if id(t) not in functions]
    for tok in tokens:
        if tok.type == "NAME" and tok not in known and tok.lower() not in CONSTANTS:
            try:
                _Evaluator(Scope(dict.fromkeys(known, 0.0)), span, column, None).name(
                    str(tok), _shift(span, tok.column, column))
            except NetlistError as err:
                raise NetlistError(err.message, span=err.span,
                                   hint=f"{err.hint}; {hint}" if "did you" in err.hint
                                   else hint) from None


@functools.lru_cache(maxsize=4096)
def _parse(text: str):
    """The parse tree of expression ``text`` (an array repeats its expressions per copy; the
    trees are only read)."""
    from .syntax import lark_parser

    return lark_parser().parse(text, start="expr")


class _Evaluator:
    def __init__(self, scope, span, base, limits):
        self.scope, self.span, self.base, self.limits = scope, span, base, limits
        self.depth = 0

    def where(self, node) -> SourceSpan:
        meta = getattr(node, "meta", None)
        col = getattr(meta, "column", None) if meta is not None and not meta.empty else None
        if col is None:
            col = getattr(node, "column", 1) or 1
        return _shift(self.span, col, self.base)

    def eval(self, node):
        from lark import Token

        if isinstance(node, Token):  # a bare expression that is one token
            return self.token(node)
        if self.depth >= self.limits.max_expression_depth:
            raise NetlistError(f"expression nested more than {self.depth} deep "
                               f"({self.limits.exceeded('max_expression_depth')})",
                               span=self.where(node), hint="split it into .param steps; "
                               + self.limits.hint("max_expression_depth"))
        self.depth += 1
        try:
            return getattr(self, "r_" + node.data)(node)
        finally:
            self.depth -= 1

    def token(self, tok):
        if tok.type == "NUMBER":
            magnitude, suffix = split(tok)
            if not suffix:  # a plain number: no span needed
                return magnitude
            return number_in_expression(str(tok), _shift(self.span, tok.column, self.base))
        if tok.type == "NAME":
            value = self.scope.lookup(tok)
            if value is not None:
                return value
            return self.name(str(tok), _shift(self.span, tok.column, self.base))
        raise AssertionError(tok.type)  # pragma: no cover

    def r_number(self, node):
        return self.token(node.children[0])

    def r_name(self, node):
        return self.token(node.children[0])

    def name(self, name, span):
        value = self.scope.lookup(name)
        if value is None:
            value = CONSTANTS.get(name.lower())
        if value is None:
            import difflib

            known = sorted(self.scope.names() | set(CONSTANTS))
            close = difflib.get_close_matches(name, known, n=1)
            raise NetlistError(f"undefined parameter {_cut(name)!r} in expression", span=span,
                               hint=f"did you mean {close[0]!r}?" if close else
                               "define it with .param NAME=value")
        return value

    def r_func(self, node):
        name = str(node.children[0])
        fn = FUNCTIONS.get(name.lower())
        span = self.where(node)
        if fn is None:
            import difflib

            close = difflib.get_close_matches(name.lower(), FUNCTIONS, n=1)
            raise NetlistError(f"unknown function {_cut(name)!r}", span=span,
                               hint=f"did you mean {close[0]!r}?" if close else
                               "known: " + ", ".join(sorted(FUNCTIONS)))
        args = [self.eval(a) for a in node.children[1:]]
        try:
            return float(fn(*args))
        except TypeError:
            raise NetlistError(f"wrong number of arguments ({len(args)}) for {name}()",
                               span=span) from None
        except (ValueError, OverflowError) as exc:
            raise NetlistError(f"{name}({', '.join(f'{a:g}' for a in args)}): {exc}",
                               span=span) from None

    def r_neg(self, node):
        op, arg = node.children
        value = self.eval(arg)
        return -value if str(op) == "-" else value

    def r_not_(self, node):
        return float(not self.eval(node.children[0]))

    def r_binop(self, node):
        left, op, right = node.children
        a, b = self.eval(left), self.eval(right)
        op = str(op)
        try:
            if op == "+":
                return a + b
            if op == "-":
                return a - b
            if op == "*":
                return a * b
            if op in ("/", "%"):
                if b == 0:
                    raise NetlistError("division by zero in expression",
                                       span=_shift(self.span, op_column(op, node), self.base),
                                       hint="check the parameter values used in the divisor")
                return a / b if op == "/" else math.fmod(a, b)
            return float(a ** b)
        except (OverflowError, ZeroDivisionError, TypeError) as exc:
            raise NetlistError(f"cannot evaluate {a:g} {op} {b:g}: {exc}",
                               span=self.where(node)) from None

    def r_compare(self, node):
        left, op, right = node.children
        a, b = self.eval(left), self.eval(right)
        return float({"<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b, "==": a == b,
                      "!=": a != b}[str(op)])

    def r_and_(self, node):
        return float(bool(self.eval(node.children[0])) and bool(self.eval(node.children[1])))

    def r_or_(self, node):
        return float(bool(self.eval(node.children[0])) or bool(self.eval(node.children[1])))

    def r_cond(self, node):
        c, a, b = node.children
        return self.eval(a) if self.eval(c) else self.eval(b)


def _cut(text: str, width: int = 60) -> str:
    """``text`` for a message: a long one is cut (the caret display shows the line)."""
    return text if len(text) <= width else text[:width - 1] + "…"


def op_column(op, node) -> int:
    tok = node.children[1]
    return getattr(tok, "column", None) or 1
