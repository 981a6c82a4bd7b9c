"""The include policy's rules at their edges: name lengths at the limit, where a name is looked
up (the including file's folder, then the search path), the include count, self-inclusion,
the hints, and what is opened (never followed through a link, checked by its descriptor,
closed once).  Each test kills mutants of pneunet/netlist/includes.py that survived
tests/netlist/test_includes.py (benchmarks/mutation.py, issue 39)."""
import os
import sys
import threading
from pathlib import Path
from types import SimpleNamespace

import pytest

from pneunet.common.errors import NetlistError
from pneunet.netlist import includes, parse_file
from pneunet.netlist.includes import IncludePolicy, Opened


def _error(top, text, **kw):
    top.write_text(text)
    with pytest.raises(NetlistError) as info:
        parse_file(top, **kw)
    return info.value


@pytest.fixture
def home(tmp_path):
    (tmp_path / "home" / "lib").mkdir(parents=True)
    (tmp_path / "shared").mkdir()
    return tmp_path / "home"


@pytest.mark.parametrize("length", [79, 80, 81, 200])
def test_a_name_in_a_message_is_cut_to_80_characters(home, length):
    name = "n" * (length - 3) + ".pn"
    err = _error(home / "top.pn", f'.include "{name}"\n')
    shown = name if length <= 80 else name[:79] + "…"
    assert err.message == f"cannot find included file {shown!r}"
    assert len(shown) == min(length, 80)


def test_name_lengths_are_refused_past_the_limits_not_at_them(home):
    """1024 characters in all and 255 per folder name are allowed (not found here);
    one more of either is refused before any lookup."""
    def message(name):
        return _error(home / "top.pn", f'.include "{name}"\n').message

    for name in ("a/" * 511 + "bb", "a" * 255):  # 1024 characters; a 255-character part
        assert len(name) in (1024, 255)
        assert message(name).startswith("cannot find included file"), name[:20]
    assert message("a/" * 511 + "bbb") == "include name of 1025 characters is too long"
    assert message("a" * 256) == "include name of 256 characters is too long"
    assert message("x/" + "a" * 256) == "include name of 258 characters is too long"


def test_blank_and_nul_names_are_not_file_names(home):
    err = _error(home / "top.pn", '.include " "\n')
    assert err.message == "' ' is not a file name"
    policy = IncludePolicy.for_netlist(home / "top.pn")
    with pytest.raises(NetlistError, match=r"'a\\x00b' is not a file name"):
        policy.resolve(SimpleNamespace(text="a\0b", span=None), home)


def test_a_name_is_looked_up_from_the_including_files_folder(home):
    """lib/a.pn's "b.pn" is lib/b.pn, never the top folder's b.pn."""
    (home / "b.pn").write_text("R9 a atm 1\n")
    (home / "lib" / "a.pn").write_text('.include "b.pn"\n')
    err = _error(home / "top.pn", '.include "lib/a.pn"\n')
    assert err.message == "cannot find included file 'b.pn'"
    assert err.span.file.endswith("a.pn")
    assert err.hint == f"paths are relative to the including file ({home / 'lib'})"


def test_the_hint_names_the_search_path_only_when_there_is_one(home, monkeypatch):
    monkeypatch.delenv("PNEUNET_PATH", raising=False)
    text = '.include "x.pn"\n'
    assert not _error(home / "top.pn", text).hint.endswith("then the search path")
    err = _error(home / "top.pn", text, include_path=[home.parent / "shared"])
    assert err.hint == f"paths are relative to the including file ({home}), then the search path"


def test_a_name_leading_outside_here_is_still_looked_up_in_the_search_path(home):
    """x.pn beside the netlist is a link out of the allowed folders: it is passed over and
    the search path's x.pn is taken (the search does not end at the refused one)."""
    (home.parent / "outside.pn").write_text("R_OUT a atm 1\n")
    (home / "x.pn").symlink_to(home.parent / "outside.pn")
    (home.parent / "shared" / "x.pn").write_text("R_SHARED a atm 1\n")
    (home / "top.pn").write_text('.include "x.pn"\n')
    elements = parse_file(home / "top.pn", include_path=[home.parent / "shared"]).circuit.elements
    assert "R_SHARED" in elements and "R_OUT" not in elements
    with pytest.raises(NetlistError, match=r"'x.pn' leads outside the allowed folders \(to "):
        parse_file(home / "top.pn")


@pytest.mark.parametrize("relative", [False, True])
def test_a_file_including_itself_is_caught_at_once(home, monkeypatch, relative):
    """At its own include line, not one level deeper (named absolute or relative)."""
    monkeypatch.chdir(home)
    (home / "top.pn").write_text('R1 a atm 1\n.include "top.pn"\n')
    with pytest.raises(NetlistError) as info:
        parse_file("top.pn" if relative else home / "top.pn")
    err = info.value
    assert err.message == "recursive .include: top.pn -> top.pn"
    assert (err.span.line, err.span.column) == (2, 10)
    assert err.span.via == () and "included from" not in err.report()


def test_a_netlist_given_as_text_includes_from_the_working_folder_first(home, monkeypatch):
    from pneunet.netlist import parse_netlist

    monkeypatch.chdir(home)
    (home / "v.pn").write_text("R_HERE a atm 1\n")
    (home.parent / "shared" / "v.pn").write_text("R_SHARED a atm 1\n")
    deck = parse_netlist('.include "v.pn"\n', include_path=[home.parent / "shared"])
    assert set(deck.circuit.elements) == {"R_HERE"}


def test_the_include_count_allows_its_limit_and_refuses_one_more(home):
    for i in range(4):
        (home / f"f{i}.pn").write_text(f"R{i} a atm 1\n")
    three = "".join(f'.include "f{i}.pn"\n' for i in range(3))
    (home / "top.pn").write_text(three)
    assert len(parse_file(home / "top.pn", limits={"max_includes": 3}).circuit.elements) == 3
    err = _error(home / "top.pn", three + '.include "f3.pn"\n', limits={"max_includes": 3})
    assert err.message.startswith("more than 3 files included in all")
    assert err.span.line == 4


@pytest.mark.parametrize("line, hint", [
    (".include", 'e.g. .include "valves.pn"'),
    ('.include "a.pn" "b.pn"', 'e.g. .include "valves.pn"'),
    ('.include "a.pn" typical', 'e.g. .include "valves.pn"'),
    (".include a=1", 'e.g. .include "valves.pn"'),
    (".lib", 'e.g. .include "valves.pn"'),
    ('.lib "a.pn" typical', ".lib sections are not supported; .lib FILE includes the whole file"),
    ('.lib "a.pn" "b.pn" typical', 'e.g. .include "valves.pn"'),
])
def test_an_include_without_one_name_is_an_error_with_its_hint(home, line, hint):
    err = _error(home / "top.pn", line + "\n")
    assert err.message == f"{line.split()[0]} needs one file name", err.message
    assert err.hint == hint and err.span.line == 1


def test_the_name_opened_is_never_followed_through_a_link(home, monkeypatch):
    """Were the checked name a link when opened (swapped in meanwhile), the open fails
    (O_NOFOLLOW) at the include line, even for a link to an allowed file."""
    (home / "v.pn").write_text("R9 a atm 1\n")
    (home / "link.pn").symlink_to(home / "v.pn")
    monkeypatch.setattr(IncludePolicy, "resolve", lambda self, item, base: home / "link.pn")
    err = _error(home / "top.pn", 'R1 a atm 1\n.include "v.pn"\n')
    assert err.message == "cannot open included 'v.pn': Too many levels of symbolic links"
    assert err.hint == "was it changed while pneunet ran?"
    assert (err.span.line, err.span.column) == (2, 10)


@pytest.mark.parametrize("through_proc", [False, True])
def test_what_was_opened_is_where_its_descriptor_points(home, monkeypatch, through_proc):
    """real_path follows the open file (renamed after the open), not its name, whether the
    name sorts after /proc/self/fd/N (/tmp/...) or before it (/proc/self/cwd/...)."""
    monkeypatch.chdir(home)
    (home / "v.pn").write_text("R9 a atm 1\n")
    name = Path("/proc/self/cwd/v.pn") if through_proc else home / "v.pn"
    with Opened(os.open(name, os.O_RDONLY), name) as opened:
        os.rename(home / "v.pn", home / "lib" / "w.pn")
        assert opened.real_path() == home / "lib" / "w.pn"
        assert opened.read_bytes() == b"R9 a atm 1\n"


def test_a_fifo_swapped_in_is_refused_without_blocking(home, monkeypatch):
    """Opened with O_NONBLOCK: a FIFO in place of the checked file (no writer) is refused at
    once as not a regular file, instead of blocking the parse forever."""
    os.mkfifo(home / "pipe.pn")
    monkeypatch.setattr(IncludePolicy, "resolve", lambda self, item, base: home / "pipe.pn")
    (home / "top.pn").write_text('R1 a atm 1\n.include "v.pn"\n')
    outcome = []

    def parse():
        try:
            parse_file(home / "top.pn")
        except Exception as exc:  # noqa: BLE001 - checked below
            outcome.append(exc)

    thread = threading.Thread(target=parse, daemon=True)
    thread.start()
    thread.join(30.0)  # a parse takes milliseconds; 30 s only when it blocks (or a loaded machine)
    if thread.is_alive():  # blocked in open(): a writer releases it
        os.close(os.open(home / "pipe.pn", os.O_WRONLY | os.O_NONBLOCK))
        thread.join(5.0)
        pytest.fail("opening the FIFO blocked")
    assert isinstance(outcome[0], NetlistError), outcome
    assert outcome[0].message.startswith("include 'v.pn' changed while it was opened")


def test_an_open_file_whose_place_is_unknown_is_refused(home, monkeypatch):
    def unknown(path):
        raise OSError("no such descriptor")

    (home / "v.pn").write_text("R9 a atm 1\n")
    monkeypatch.setattr(includes.os, "readlink", unknown)
    err = _error(home / "top.pn", '.include "v.pn"\n')
    assert err.message.startswith("include 'v.pn' changed while it was opened and now leads "
                                  "outside the allowed folders (to None)")
    assert err.span.line == 1


def test_included_files_are_closed_once(home):
    """No descriptor is left open by a parse with includes, a refused one among them; an
    Opened closed twice closes nothing else the second time."""
    (home / "v.pn").write_text("* included twice\n")
    (home / "lib" / "w.pn").write_text('.include "../v.pn"\n')
    (home / "top.pn").write_text('R1 a atm 1\n.include "lib/w.pn"\n.include "v.pn"\n')
    before = len(os.listdir("/proc/self/fd"))
    parse_file(home / "top.pn", limits={"max_includes": 3})
    _error(home / "top.pn", 'R1 a atm 1\n.include "lib/w.pn"\n.include "v.pn"\n',
           limits={"max_includes": 2})
    assert len(os.listdir("/proc/self/fd")) == before
    opened = Opened(os.open(home / "v.pn", os.O_RDONLY), home / "v.pn")
    opened.close()
    assert opened.fd < 0
    other = os.open(home / "v.pn", os.O_RDONLY)  # likely the number just freed
    try:
        opened.close()
        os.fstat(other)
    finally:
        os.close(other)


def test_a_link_vanishing_while_a_name_is_resolved_is_an_error_not_a_traceback(home,
                                                                              monkeypatch):
    """realpath raises FileNotFoundError when a link on the way is removed between its
    lstat and its readlink (a folder swapped back, as in test_includes' swap loop): the
    candidate is passed over for the search path's (none left: not found); the including
    file's own place: a located error."""
    real = os.path.realpath
    (home / "v.pn").write_text("R9 a atm 1\n")
    (home.parent / "shared" / "v.pn").write_text("R_SHARED a atm 1\n")

    def vanishing(path, *args, **kw):
        if sys._getframe(1).f_code.co_name == vanishing.caller and "shared" not in str(path):
            raise FileNotFoundError(2, "No such file or directory", str(path))
        return real(path, *args, **kw)

    monkeypatch.setattr(includes.os.path, "realpath", vanishing)
    vanishing.caller = "resolve"  # the candidate in the netlist's folder, not shared/'s
    (home / "top.pn").write_text('R1 a atm 1\n.include "v.pn"\n')
    deck = parse_file(home / "top.pn", include_path=[home.parent / "shared"])
    assert "R_SHARED" in deck.circuit.elements and "R9" not in deck.circuit.elements
    err = _error(home / "top.pn", 'R1 a atm 1\n.include "v.pn"\n')
    assert err.message == "cannot find included file 'v.pn'" and err.span.line == 2
    vanishing.caller = "_here"  # the including file itself
    err = _error(home / "top.pn", 'R1 a atm 1\n.include "v.pn"\n')
    assert err.message.endswith("' changed while it was read") and err.span.line == 2
    assert err.span.file.endswith("top.pn")
