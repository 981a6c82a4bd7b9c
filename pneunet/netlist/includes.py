"""``.include`` / ``.lib``: where an included file may come from, checked before it is opened.

A name is resolved relative to the including file, then in each folder of the search path
(``--include-path``, then ``PNEUNET_PATH``).  After symbolic links are resolved, the file must
lie under the top netlist's folder or a search-path folder and be a regular file; absolute
names, over-long names and files elsewhere are errors at the ``.include`` line.  A file is opened once and
what was opened is checked (:meth:`IncludePolicy.open`), never checked by name and then
opened again: a folder swapped for a symbolic link meanwhile cannot lead outside.
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from pathlib import Path

from ..common.errors import NetlistError
from .limits import DEFAULT, Limits
from .syntax import SourceText, Str, Word, read_source

KEYWORDS = (".include", ".inc", ".lib")
#: characters in an include name, at most (a longer name is refused before any lookup)
MAX_NAME = 1024


@dataclass(frozen=True)
class IncludePolicy:
    """The folders whose files a netlist may include (resolved, symbolic links followed)."""

    roots: tuple

    @classmethod
    def for_netlist(cls, top: Path | None, include_path=()) -> "IncludePolicy":
        """The top netlist's folder (the cwd for text), ``include_path``, then ``PNEUNET_PATH``."""
        home = Path(os.path.realpath(top)).parent if top is not None else Path.cwd().resolve()
        extra = [*include_path, *filter(None, os.environ.get("PNEUNET_PATH", "").split(os.pathsep))]
        return cls((home, *(Path(os.path.realpath(p)) for p in extra)))

    def allows(self, path: Path) -> bool:
        return any(path == root or path.is_relative_to(root) for root in self.roots)

    def open(self, item, base: Path) -> "Opened":
        """The file ``item`` names, found as :meth:`resolve` finds it, opened once; then what
        was opened (the descriptor's own path) is checked, so that a folder swapped for a
        symbolic link between the check and the open cannot lead outside the roots."""
        path = self.resolve(item, base)
        try:
            fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK
                         | getattr(os, "O_CLOEXEC", 0))
        except OSError as exc:
            raise NetlistError(f"cannot open included {_short(item.text)!r}: "
                               f"{exc.strerror or exc}", span=item.span,
                               hint="was it changed while pneunet ran?") from None
        opened = Opened(fd, path)
        real = opened.real_path()
        if not stat.S_ISREG(os.fstat(fd).st_mode) or real is None or not self.allows(real):
            opened.close()
            raise NetlistError(f"include {_short(item.text)!r} changed while it was opened "
                               f"and now leads outside the allowed folders (to "
                               f"{_short(str(real))})", span=item.span,
                               hint="a folder on the way was replaced by a symbolic link")
        return opened

    def resolve(self, item, base: Path) -> Path:
        """The file ``item`` names, found from ``base`` (the including file's folder) or the
        search path; an error at ``item`` if the policy forbids it.  Nothing is opened
        (:meth:`open` opens it and checks what it opened)."""
        name = item.text
        rule = "includes must stay under " + " or ".join(str(r) for r in self.roots)
        if len(name) > MAX_NAME or any(len(part) > 255 for part in name.split("/")):
            raise NetlistError(f"include name of {len(name)} characters is too long",
                               span=item.span,
                               hint=f"at most {MAX_NAME} characters, 255 per folder name")
        if "\0" in name or not name.strip():
            raise NetlistError(f"{_short(name)!r} is not a file name", span=item.span)
        if os.path.isabs(name) or name.startswith("~"):
            raise NetlistError(f"absolute include path {_short(name)!r} is not allowed",
                               span=item.span,
                               hint="write it relative to the including file, or add its "
                                    "folder with --include-path or PNEUNET_PATH")
        refused = None
        for folder in (base, *self.roots[1:]):
            try:  # realpath raises when a link on the way vanishes as it is read
                path = Path(os.path.realpath(folder / name))
            except OSError:
                continue
            if not self.allows(path):
                refused = refused or path
                continue
            try:
                mode = os.stat(path).st_mode
            except OSError:
                continue
            if stat.S_ISDIR(mode):
                raise NetlistError(f"included {_short(name)!r} is a folder, not a file",
                                   span=item.span)
            if not stat.S_ISREG(mode):
                raise NetlistError(f"included {_short(name)!r} is not a regular file (a device, "
                                   "pipe or socket)", span=item.span)
            return path
        if refused is not None:
            raise NetlistError(f"include {_short(name)!r} leads outside the allowed folders "
                               f"(to {_short(str(refused))})", span=item.span,
                               hint=rule + "; add a folder with --include-path or PNEUNET_PATH")
        raise NetlistError(f"cannot find included file {_short(name)!r}", span=item.span,
                           hint=f"paths are relative to the including file ({base})" +
                           (", then the search path" if len(self.roots) > 1 else ""))


class Opened:
    """A file opened by :meth:`IncludePolicy.open` (a context manager that closes it):
    ``path`` its name when checked, ``reader`` a name that reads the very file opened
    (``/proc/self/fd/N`` on Linux, else ``path``)."""

    def __init__(self, fd: int, path: Path):
        self.fd, self.path = fd, path
        proc = Path(f"/proc/self/fd/{fd}")
        self.reader = proc if proc.exists() else path

    def real_path(self) -> Path | None:
        """Where the descriptor's file lies now (its inode's path), or None if unknown."""
        if self.reader == self.path:
            return Path(os.path.realpath(self.path))
        try:
            return Path(os.readlink(self.reader))
        except OSError:
            return None

    def read_bytes(self) -> bytes:
        os.lseek(self.fd, 0, os.SEEK_SET)
        with os.fdopen(os.dup(self.fd), "rb") as fh:
            return fh.read()

    def close(self) -> None:
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _here(src: SourceText, item) -> Path | None:
    """The including file, symbolic links resolved (None for netlist text); an error at
    ``item`` if a folder on the way was swapped while it was read."""
    if src.name == "<netlist>":
        return None
    try:
        return Path(os.path.realpath(src.name))
    except OSError:
        raise NetlistError(f"{_short(src.name)!r} changed while it was read", span=item.span,
                           hint="a folder on the way was replaced while pneunet ran") from None


def _short(text: str, width: int = 80) -> str:
    return text if len(text) <= width else text[:width - 1] + "…"


def expand(src: SourceText, policy: IncludePolicy, limits: Limits = DEFAULT,
           chain: tuple = (), count: list | None = None):
    """The statements of ``src`` with each ``.include`` replaced by the included file's
    (``count``: files included so far, repeats counted; a file including another twice,
    twenty levels deep, would make 2^20)."""
    count = [0] if count is None else count
    for st in src.statements:
        if not (st.is_directive and st.keyword in KEYWORDS):
            yield st
            continue
        if len(st.items) != 2 or not isinstance(st.items[1], (Word, Str)):
            hint = ".lib sections are not supported; .lib FILE includes the whole file" \
                if st.keyword == ".lib" and len(st.items) == 3 else 'e.g. .include "valves.pn"'
            raise NetlistError(f"{st.head} needs one file name", span=st.span, hint=hint)
        item = st.items[1]
        if len(chain) >= limits.max_include_depth:
            raise NetlistError(f"includes nested {len(chain) + 1} deep "
                               f"({limits.exceeded('max_include_depth')})", span=item.span,
                               hint=limits.hint("max_include_depth"))
        here = _here(src, item)
        opened = policy.open(item, here.parent if here else policy.roots[0])
        target = opened.path
        files = ([here] if here else []) + [path for path, _ in chain]
        with opened:
            if target in files:
                loop = " -> ".join(p.name for p in [*reversed(files), target])
                raise NetlistError(f"recursive .include: {loop}", span=item.span)
            count[0] += 1
            if count[0] > limits.max_includes:
                raise NetlistError(f"more than {limits.max_includes} files included in all, "
                                   f"repeats counted ({limits.exceeded('max_includes')})",
                                   span=item.span, hint=limits.hint("max_includes"))
            via = (str(st.span).rsplit(":", 1)[0], *item.span.via)
            try:
                included = read_source(target, limits=limits, via=via, opened=opened)
            except NetlistError as err:
                if err.span is not None:
                    raise
                raise NetlistError(err.message, span=item.span, hint=err.hint) from None
        yield from expand(included, policy, limits, ((target, st.span), *chain), count)
