"""The JSON-lines store of a sweep: one finished point per line, appended as it
finishes, read back on a rerun.

Each record is written with a single ``write`` of the whole line, so a kill leaves at
most the last line cut short; :func:`open_store` truncates such a torn tail before
appending (else the next record would be glued to it and that point recomputed on
every rerun), and :func:`read_store` skips a line that is not valid JSON.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

from ..common.errors import PneunetError


def read_store(path) -> dict:
    """Records of a store by key (torn or corrupt lines are skipped)."""
    done = {}
    path = Path(path)
    if not path.exists():
        return done
    with path.open("rb") as fh:
        for line in fh:
            if not line.endswith(b"\n"):
                continue  # cut by a kill while written
            try:
                rec = json.loads(line)
            except ValueError:
                continue
            if isinstance(rec, dict) and "key" in rec:
                done[rec["key"]] = rec
    return done


def fingerprint(build, analysis) -> str:
    """A digest of what sets a point's result besides its parameters: the circuit (a
    netlist elaborated with its defaults, so every included file, table, .model, analysis
    and .meas line counts), the analysis and its settings, and pneunet's version.  A store
    record with another fingerprint is not reused."""
    import hashlib

    from .. import __version__

    deck = getattr(build, "deck", None)
    if deck is not None:
        circuit = deck().to_netlist() + repr(sorted(getattr(build, "options", {}).items()))
    else:
        circuit = f"{getattr(build, '__module__', '')}.{getattr(build, '__qualname__', '')}"
        circuit = circuit if circuit != "." else repr(build)
    settings = {k: v for k, v in sorted(vars(analysis).items()) if k != "builder"} \
        if hasattr(analysis, "__dict__") else repr(analysis)
    kind = next((c for c in type(analysis).__mro__ if c.__module__.startswith("pneunet.")),
                type(analysis)).__qualname__  # a subclass that only wraps it: the same kind
    text = "\n".join((__version__, circuit, kind, repr(settings)))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def check_writable(path, what: str, hint: str) -> None:
    """A PneunetError now, before any work, when the file ``path`` (the sweep's table,
    plot or store) cannot be written; its directories are made."""
    import tempfile

    path = Path(path)
    try:
        blocker = next((d for d in path.parents if d.exists() and not d.is_dir()), None)
        if blocker is not None:
            raise NotADirectoryError(20, f"{blocker} is a file, not a directory")
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.is_dir():
            raise IsADirectoryError(21, "it is a directory")
        with tempfile.NamedTemporaryFile(dir=path.parent, prefix=".pneunet-write-test-"):
            pass
    except OSError as err:
        raise PneunetError(f"cannot write the {what} {path}: {err.strerror or err}",
                           hint=hint) from None


def open_store(path) -> int:
    """A file descriptor for appending to the store at ``path`` (directories made, a
    torn last line cut off); a PneunetError before any work when it cannot be written."""
    check_writable(path, "sweep store", "choose a writable place with --store or --out")
    fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_APPEND, 0o644)
    size = os.fstat(fd).st_size
    if size and os.pread(fd, 1, size - 1) != b"\n":
        os.ftruncate(fd, _end_of_last_line(fd, size))
    return fd


def _end_of_last_line(fd: int, size: int, block: int = 1 << 16) -> int:
    """Offset just after the last newline before ``size`` (0 without one)."""
    end = size
    while end > 0:
        start = max(0, end - block)
        cut = os.pread(fd, end - start, start).rfind(b"\n")
        if cut >= 0:
            return start + cut + 1
        end = start
    return 0


def append(fd: int, record: dict, default=None) -> None:
    """Write one record as one line with a single system call."""
    data = (json.dumps(record, default=default) + "\n").encode()
    while data:
        data = data[os.write(fd, data):]
