"""Netlist text -> statements with source spans (lark does the lexing and parsing).

Comments are blanked out (replaced by spaces) before parsing so that every token
keeps its file line and column.  A statement is a list of items:

* :class:`Word` — a bare word (name, node, number with unit, ``{expr}``...);
* :class:`Str` — a quoted string (file names);
* :class:`Call` — ``NAME(args)`` (waveforms, ``VALVE(...)``, ``p(node)``);
* :class:`Group` — ``(args)`` without a name;
* :class:`Pair` — ``key=value``.
"""
from __future__ import annotations

import bisect
import functools
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ..common.errors import NetlistError, SourceSpan


# -- items ---------------------------------------------------------------------------
@dataclass
class Item:
    span: SourceSpan


@dataclass
class Word(Item):
    text: str

    def __str__(self):
        return self.text


@dataclass
class Str(Item):
    text: str

    def __str__(self):
        return f'"{self.text}"'


@dataclass
class Call(Item):
    name: str
    args: list

    def __str__(self):
        return f"{self.name}({' '.join(str(a) for a in self.args)})"


class RawArgs(Sequence):
    """The plain words of a ``TABLE(…)`` or ``PWL(…)`` body, read without lark (a
    300,000-pair table took 40 s there): their texts and (line, column) places; a
    :class:`Word` is made only when an item is asked for (an error, a PWL value, or a
    TABLE where it does not belong)."""

    def __init__(self, texts: list, places: list, name: str, lines: list, via: tuple):
        self.texts, self.places = texts, places
        self._where = (name, lines, via)

    def __len__(self):
        return len(self.texts)

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        return Word(self.span(index), self.texts[index])

    def span(self, index: int) -> SourceSpan:
        name, lines, via = self._where
        return _span_in(name, lines, *self.places[index], via=via)


@dataclass
class Group(Item):
    args: list

    def __str__(self):
        return f"({' '.join(str(a) for a in self.args)})"


@dataclass
class Pair(Item):
    key: Item
    value: Item

    def __str__(self):
        return f"{self.key}={self.value}"


@dataclass
class Statement:
    items: list
    span: SourceSpan
    #: file the statement comes from (for .include relative paths)
    path: Path | None = None

    @property
    def head(self) -> str:
        first = self.items[0]
        return first.text if isinstance(first, Word) else ""

    @property
    def is_directive(self) -> bool:
        return self.head.startswith(".")

    @property
    def keyword(self) -> str:
        return self.head.lower()


@dataclass
class SourceText:
    """A parsed file: its statements and its title (first '*' comment line)."""

    name: str
    lines: list
    statements: list = field(default_factory=list)
    title: str = ""


# -- lark -----------------------------------------------------------------------------
@functools.lru_cache(maxsize=1)
def lark_parser():
    """The shared LALR parser (netlist and expression start symbols).  Building its
    tables costs a process ~0.1 s; lark keeps them in :func:`grammar_cache` (checked
    against the grammar's, the options' and lark's own hash, rebuilt when one changed)."""
    from importlib.resources import files

    from lark import Lark

    grammar = files("pneunet.netlist").joinpath("grammar.lark").read_text(encoding="utf-8")
    return Lark(grammar, parser="lalr", start=["netlist", "expr"], propagate_positions=True,
                maybe_placeholders=False, cache=grammar_cache())


def grammar_cache():
    """The file of the built parser tables, in the user's own cache folder
    (``$XDG_CACHE_HOME/pneunet``, default ``~/.cache/pneunet``, created private); False
    (no cache) when that folder cannot be made or others could write to it: the file is a
    pickle, read only from a folder no one else controls."""
    import os
    import stat

    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    folder = os.path.join(base, "pneunet")
    try:
        os.makedirs(folder, mode=0o700, exist_ok=True)
        info = os.stat(folder)
    except (OSError, ValueError):
        return False
    mine = not hasattr(os, "getuid") or info.st_uid == os.getuid()
    if not (mine and stat.S_ISDIR(info.st_mode) and not info.st_mode & 0o022
            and os.access(folder, os.W_OK)):
        return False
    return os.path.join(folder, "netlist-grammar.lark-cache")


_COMMENT_LINE = re.compile(r"^[ \t]*\*")
#: control characters refused outside comments (NUL, ESC, ...; not tab, CR, LF, form feed)
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0e-\x1f\x7f-\x9f]")


def blank_comments(text: str) -> tuple[str, str]:
    """Blank '*' comment lines and ';' comments; return (text, title)."""
    out, title = [], ""
    for line in text.split("\n"):
        if _COMMENT_LINE.match(line):
            if not title and not out and line.strip("* \t\r"):
                title = line.strip().lstrip("*").strip()
            out.append(" " * len(line.rstrip("\r")))
            continue
        cut = line.find(";")
        if cut >= 0:
            line = line[:cut] + " " * (len(line) - cut)
        out.append(line)
    return "\n".join(out), title


def parse_text(text: str, name: str = "<netlist>", path: Path | None = None, *,
               limits=None, via: tuple = ()) -> SourceText:
    """Parse netlist text into statements (no meaning attached yet); ``via`` names the
    ``.include`` lines through which the file was reached, for error messages."""
    from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

    from .limits import DEFAULT

    limits = limits or DEFAULT
    _span = functools.partial(_span_in, via=via)
    text = text.replace("\t", " ")
    lines = text.split("\n")
    for number, line in enumerate(lines, 1):
        if len(line) > limits.max_line_length:
            raise NetlistError(f"line of {len(line)} characters is too long "
                               f"({limits.exceeded('max_line_length')})",
                               span=_span(name, lines, number, limits.max_line_length + 1),
                               hint="split it with '+' continuation lines; "
                                    + limits.hint("max_line_length"))
    clean, title = blank_comments(text)
    control = _CONTROL.search(clean)
    if control:
        line = clean.count("\n", 0, control.start()) + 1
        column = control.start() - clean.rfind("\n", 0, control.start())
        raise NetlistError(f"control character {control.group()!r} in the netlist",
                           span=_span(name, lines, line, column),
                           hint="names, nodes and values are printable text: remove it (a "
                                "binary file, or a paste from a terminal?)")
    first = clean.lstrip(" \n\r")
    if first.startswith("+"):
        line = clean[:len(clean) - len(first)].count("\n") + 1
        raise NetlistError("continuation line '+' without a line to continue",
                           span=_span(name, lines, line, lines[line - 1].find("+") + 1))
    if not clean.endswith("\n"):
        clean += "\n"
    clean, tables = _plain_tables(clean, name, lines, via)
    try:
        tree = lark_parser().parse(clean, start="netlist")
    except UnexpectedInput as err:
        line, column = err.line, err.column
        if line < 1:  # error at end of input
            line = len(lines)
            column = len(lines[-1]) + 1
        if isinstance(err, UnexpectedToken):
            tok = err.token
            if tok.type in ("_NL", "$END"):
                msg = "unexpected end of line"
                hint = "a '(' or '{' is not closed, or a key= has no value"
                column = min(column, len(lines[line - 1]) + 1) if line <= len(lines) else column
            elif tok.type == "EQUAL":
                msg, hint = "unexpected '='", "write key=value without spaces before a value, " \
                                              "and only one '=' per parameter"
            elif tok.type == "RPAR":
                msg, hint = "unexpected ')'", "parentheses are not balanced"
            else:
                value = tok.value if len(tok.value) <= 60 else tok.value[:59] + "…"
                msg, hint = f"unexpected {value!r}", None
        elif isinstance(err, UnexpectedCharacters):
            ch = lines[line - 1][column - 1] if line <= len(lines) and column <= len(lines[line - 1]) else "?"
            msg = f"unexpected character {ch!r}"
            hint = "a '{' is not closed on this line" if ch == "{" else \
                "a '}' has no matching '{'" if ch == "}" else None
        else:  # pragma: no cover
            msg, hint = str(err), None
        raise NetlistError(msg, span=_span(name, lines, line, column), hint=hint) from None
    src = SourceText(name, lines, title=title)
    for st in tree.children:
        items = [_item(child, name, lines, _span, tables) for child in st.children]
        src.statements.append(Statement(items, items[0].span, path))
    return src


_TABLE_OPEN = re.compile(r"(?<![^\s=(,])(?:TABLE|PWL)\(", re.IGNORECASE)
_CONTINUED = re.compile(r"(?:\n[ \t\r]*)+\+")


def _plain_tables(clean: str, name, lines, via) -> tuple[str, dict]:
    """``clean`` with the body of each ``TABLE(…)`` or ``PWL(…)`` that holds only plain
    words (numbers with their units, on ``+`` lines) blanked out, and those bodies as
    :class:`RawArgs` by the (line, column) of their call.  A body with anything else (braces, commas, quotes,
    '=', parentheses) is left to lark, which reports what is wrong in it."""
    tables, out, done, counted, line = {}, [], 0, 0, 1
    for match in _TABLE_OPEN.finditer(clean):
        start, end = match.end(), clean.find(")", match.end())
        line_start = clean.rfind("\n", 0, match.start()) + 1
        before, body = clean[line_start:match.start()], clean[start:max(end, start)]
        if end < 0 or any(c in body for c in '({"=,') or before.count('"') % 2 or \
                before.count("{") > before.count("}") or \
                body.count("\n") != sum(m.group().count("\n")
                                        for m in _CONTINUED.finditer(body)):
            continue
        line += clean.count("\n", counted, match.start())
        counted = match.start()
        column = match.start() - line_start + 1
        plain = _CONTINUED.sub(lambda m: m.group()[:-1] + " ", body)  # without the '+' marks
        breaks = [m.start() for m in re.finditer("\n", body)]
        texts, places = [], []
        for word in re.finditer(r"\S+", plain):
            k = bisect.bisect(breaks, word.start())
            texts.append(word.group())
            places.append((line + k, column + start - match.start() + word.start() if not k
                           else word.start() - breaks[k - 1]))
        tables[line, column] = RawArgs(texts, places, name, lines, via)
        blank = list(re.sub(r"[^\n]", " ", body))
        for m in _CONTINUED.finditer(body):
            blank[m.end() - 1] = "+"
        out += [clean[done:start], "".join(blank)]
        done = end
    return "".join(out) + clean[done:], tables


def _span_in(name, lines, line, column, via=()) -> SourceSpan:
    text = lines[line - 1] if 1 <= line <= len(lines) else ""
    return SourceSpan(name, line, max(column, 1), text, via)


def _item(node, name, lines, span_of, tables) -> Item:
    kind = node.data
    span = span_of(name, lines, node.meta.line, node.meta.column)
    if kind == "word":
        return Word(span, str(node.children[0]))
    if kind == "string":
        return Str(span, str(node.children[0])[1:-1])
    if kind == "pair":
        return Pair(span, _item(node.children[0], name, lines, span_of, tables),
                    _item(node.children[1], name, lines, span_of, tables))
    if kind in ("call", "group"):
        children = list(node.children)
        head = str(children.pop(0)) if kind == "call" else None
        args = tables.get((span.line, span.column), []) if kind == "call" else []
        for ch in children:
            if getattr(ch, "data", None) == "args":
                args = [_item(a, name, lines, span_of, tables) for a in ch.children]
        return Call(span, head, args) if kind == "call" else Group(span, args)
    raise AssertionError(kind)  # pragma: no cover


def read_source(path: Path, *, limits=None, via: tuple = (), opened=None) -> SourceText:
    """The parsed netlist file: UTF-8, with or without a byte-order mark; a folder, a
    device or a pipe is refused before it is opened (``/dev/zero`` never ends).  An
    included file is read from ``opened`` (:class:`.includes.Opened`), named ``path``."""
    import stat

    try:
        if opened is not None:
            raw = opened.read_bytes()
        elif not stat.S_ISREG(path.stat().st_mode):
            raise NetlistError(f"{path} is not a regular file (a folder, device or pipe)",
                               where=str(path), hint="name a netlist file")
        else:
            raw = path.read_bytes()
    except OSError as exc:
        raise NetlistError(f"cannot read {path}: {exc.strerror or exc}", where=str(path)) \
            from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        start = raw.rfind(b"\n", 0, exc.start) + 1
        end = raw.find(b"\n", exc.start)
        column = len(raw[start:exc.start].decode("utf-8-sig")) + 1  # characters, not bytes
        text = raw[start:end if end >= 0 else len(raw)].decode("utf-8-sig", errors="replace")
        raise NetlistError(f"byte 0x{raw[exc.start]:02x} is not UTF-8 text",
                           span=SourceSpan(str(path), line, column, text, via),
                           hint="save the netlist as UTF-8 (netlists are plain text)") from None
    return parse_text(text, str(path), path, limits=limits, via=via)
