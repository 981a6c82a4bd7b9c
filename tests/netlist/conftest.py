"""``opened_files``: the data files a call opens, watched through Python's "open" audit
event (open, io.open, os.open, Path.open/read_*); imports, entry-point scans and files of
the installed program and libraries (grammar.lark, pint's unit definitions, the parser
tables lark keeps in the user's cache) are left out.
An audit hook cannot be removed, so one hook records only while a call is watched."""
import os
import sys

import pytest

import pneunet
from pneunet.netlist.syntax import grammar_cache

#: the program's and the libraries' own files
CODE = tuple(os.path.realpath(p) + os.sep for p in
             {sys.prefix, sys.base_prefix, os.path.dirname(pneunet.__file__)})
#: the parser tables lark keeps for pneunet, read at a process's first parse
OWN = {os.path.realpath(p) for p in [grammar_cache()] if p}

_OPENED: list = []
_WATCHING: list = []


def _audit(event, args):
    if not (_WATCHING and event == "open" and args
            and isinstance(args[0], (str, bytes, os.PathLike))):
        return
    frame = sys._getframe(1)
    while frame is not None:
        if "importlib" in frame.f_code.co_filename:
            return
        frame = frame.f_back
    _OPENED.append(os.path.realpath(os.fsdecode(args[0])))


sys.addaudithook(_audit)


def watch(fn):
    """(files opened by ``fn()``, its exception or None)."""
    _OPENED.clear()
    _WATCHING.append(True)
    try:
        fn()
        error = None
    except Exception as exc:  # noqa: BLE001 - returned to the test
        error = exc
    finally:
        _WATCHING.clear()
    return [p for p in _OPENED if not p.startswith(CODE) and p not in OWN], error


@pytest.fixture
def opened_files():
    return watch
