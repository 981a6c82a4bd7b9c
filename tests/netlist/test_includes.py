"""The include policy: files outside the netlist's folder and the search path are refused at
the .include line before they are opened; errors in included files name the include chain."""
import os
from pathlib import Path

import pytest

from pneunet.interfaces.cli import main
from pneunet.common.errors import NetlistError
from pneunet.netlist import parse_file

LONG = "a" * 5000
HOSTILE = {  # include name -> expected message fragment
    "/etc/passwd": "absolute include path '/etc/passwd' is not allowed",
    "/etc/hostname": "absolute include path '/etc/hostname' is not allowed",
    "/proc/self/environ": "absolute include path '/proc/self/environ' is not allowed",
    "/dev/zero": "absolute include path '/dev/zero' is not allowed",
    "../../../../../../etc/passwd": "leads outside the allowed folders (to /etc/passwd)",
    "../../../../../../proc/self/environ": "leads outside the allowed folders",
    "link_passwd.pn": "leads outside the allowed folders (to /etc/passwd)",
    "link_out/x.pn": "leads outside the allowed folders",
    "lib": "included 'lib' is a folder, not a file",
    LONG: "include name of 5000 characters is too long",
    "~/.bashrc": "absolute include path '~/.bashrc' is not allowed",
}


@pytest.fixture
def project(tmp_path):
    top = tmp_path / "project"
    (top / "lib").mkdir(parents=True)
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "x.pn").write_text("R9 a atm 1\n")
    (top / "link_passwd.pn").symlink_to("/etc/passwd")
    (top / "link_out").symlink_to(tmp_path / "outside")
    return top


@pytest.mark.parametrize("name", list(HOSTILE), ids=lambda n: n[:30])
def test_hostile_include_is_refused_before_it_is_opened(project, name, capsys, opened_files):
    net = project / "top.pn"
    net.write_text(f'P1 a 200kPa\nR1 a atm 1\n.include "{name}"\nV1 a 10mL\n')
    opened, err = opened_files(lambda: parse_file(net))
    assert isinstance(err, NetlistError)
    assert (err.span.line, err.span.column) == (3, 10)
    assert HOSTILE[name] in err.message, err.message
    assert opened == [os.path.realpath(net)]  # the netlist itself, nothing else
    assert main(["check", str(net)]) == 2
    out = capsys.readouterr().err
    assert "Traceback" not in out and "root:" not in out and len(out) < 1000


def test_device_and_fifo_in_the_project_are_refused_unopened(project, opened_files):
    os.mkfifo(project / "pipe.pn")
    (project / "dev.pn").symlink_to("/dev/zero")
    for name, fragment in (("pipe.pn", "not a regular file"), ("dev.pn", "leads outside")):
        (project / "top.pn").write_text(f'.include "{name}"\n')
        opened, err = opened_files(lambda: parse_file(project / "top.pn"))
        assert isinstance(err, NetlistError) and fragment in err.message
        assert opened == [os.path.realpath(project / "top.pn")]


def test_search_path_and_pneunet_path_widen_the_roots(project, monkeypatch, capsys):
    shared = project.parent / "outside"
    net = project / "top.pn"
    net.write_text('P1 a 200kPa\nR1 a atm 1\nV1 a 10mL\n.include "x.pn"\n')
    with pytest.raises(NetlistError, match="cannot find included file 'x.pn'"):
        parse_file(net)
    assert "R9" in parse_file(net, include_path=[shared]).circuit.elements
    assert main(["check", str(net), "--include-path", str(shared)]) == 0
    monkeypatch.setenv("PNEUNET_PATH", str(shared))
    assert "R9" in parse_file(net).circuit.elements
    # a path through the search folder still may not climb out of it
    net.write_text('.include "../outside/x.pn"\n')
    monkeypatch.delenv("PNEUNET_PATH")
    with pytest.raises(NetlistError, match="leads outside"):
        parse_file(net)


def test_error_in_an_included_file_names_file_line_and_chain(project):
    (project / "lib" / "b.pn").write_text("* b\nR9 a b 1 foo=2\n")
    (project / "lib" / "a.pn").write_text('.include "b.pn"\n')
    (project / "top.pn").write_text('P1 a 200kPa\n.include "lib/a.pn"\n')
    with pytest.raises(NetlistError) as info:
        parse_file(project / "top.pn")
    err = info.value
    assert (Path(err.span.file).name, err.span.line, err.span.column) == ("b.pn", 2, 10)
    assert err.span.via == (f"{project / 'lib' / 'a.pn'}:1", f"{project / 'top.pn'}:2")
    report = err.report()
    assert f"included from {project / 'lib' / 'a.pn'}:1" in report
    assert f"included from {project / 'top.pn'}:2" in report


def test_include_depth_is_a_named_limit(project):
    for i in range(5):
        (project / f"n{i}.pn").write_text(f'.include "n{i + 1}.pn"\n')
    (project / "n5.pn").write_text("R1 a atm 1\n")
    parse_file(project / "n0.pn")
    with pytest.raises(NetlistError) as info:
        parse_file(project / "n0.pn", limits={"max_include_depth": 3})
    assert "includes nested 4 deep (limit max_include_depth = 3)" in info.value.message
    assert info.value.span.file.endswith("n3.pn")  # its include of n4 is the 4th level


def test_lib_is_an_include(project):
    (project / "v.pn").write_text(".model fast VALVE(axi Rf=0.3)\n")
    (project / "top.pn").write_text('.lib "v.pn"\nP1 a 200kPa\nX1 a atm atm fast\n')
    assert parse_file(project / "top.pn").circuit.elements["X1"].kind == "valve"
    (project / "top.pn").write_text('.lib "v.pn" typical\n')
    with pytest.raises(NetlistError, match=".lib needs one file name"):
        parse_file(project / "top.pn")


def test_an_unreadable_included_file_is_reported_at_the_include(project, monkeypatch):
    from pneunet.netlist import includes

    (project / "v.pn").write_text("R9 a atm 1\n")
    (project / "top.pn").write_text('P1 a 200kPa\n.include "v.pn"\n')

    def denied(path, **kw):
        raise NetlistError(f"cannot read {path}: Permission denied")

    monkeypatch.setattr(includes, "read_source", denied)
    with pytest.raises(NetlistError) as info:
        parse_file(project / "top.pn")
    assert (info.value.span.line, info.value.span.column) == (2, 10)
    assert "Permission denied" in info.value.message


def test_limits_apply_inside_included_files(project):
    (project / "v.pn").write_text("R9 a atm 1 ; " + "x" * 200 + "\n")
    (project / "top.pn").write_text('P1 a 200kPa\n.include "v.pn"\n')
    with pytest.raises(NetlistError) as info:
        parse_file(project / "top.pn", limits={"max_line_length": 100})
    assert info.value.span.file.endswith("v.pn") and info.value.span.line == 1
    assert "max_line_length = 100" in info.value.message


def test_includes_that_double_at_every_level_are_bounded(project):
    """n0 includes n1 twice, n1 includes n2 twice ... (2^19 files without a total cap)."""
    for i in range(19):
        (project / f"n{i}.pn").write_text(f'.include "n{i + 1}.pn"\n.include "n{i + 1}.pn"\n')
    (project / "n19.pn").write_text(".param a=1\n")
    with pytest.raises(NetlistError) as info:
        parse_file(project / "n0.pn")
    assert "more than 1000 files included in all, repeats counted (limit max_includes = 1000)" \
        in info.value.message


def _swap_setup(tmp_path):
    """home/real/{secret.pn,secret.csv} inside, outside/ with files of the same names whose
    element and values must never be read; home/top.pn includes and reads both."""
    home, outside = tmp_path / "home", tmp_path / "outside"
    (home / "real").mkdir(parents=True)
    outside.mkdir()
    (home / "real" / "secret.pn").write_text("R_INSIDE a atm 1\n")
    (outside / "secret.pn").write_text("R_OUTSIDE a atm 1\n")
    (home / "real" / "secret.csv").write_text("time_s,p_kPa\n0,200\n1,200\n")
    (outside / "secret.csv").write_text("time_s,p_kPa\n0,777\n1,777\n")
    top = home / "top.pn"
    top.write_text('P1 a 200kPa\nV1 a 1mL\n.include "real/secret.pn"\n'
                   'P2 b PWL(FILE="real/secret.csv")\nR2 b atm 1\nV2 b 1mL\n')
    return home, outside, top


def _swap(home, outside):
    """real/ becomes a symbolic link to outside/ (the folder kept as real.bak)."""
    os.rename(home / "real", home / "real.bak")
    os.symlink(outside, home / "real")


def _unswap(home):
    os.unlink(home / "real")
    os.rename(home / "real.bak", home / "real")


def _outcome(top):
    try:
        deck = parse_file(top)
    except NetlistError as err:
        assert "777" not in err.report() and "R_OUTSIDE" not in err.report(), err.report()
        return "refused"
    assert "R_OUTSIDE" not in deck.circuit.elements
    assert deck.circuit.elements["P2"].params["value"].value(0.5) == pytest.approx(200.0)
    return "inside"


@pytest.mark.parametrize("kind", [".include", "PWL(FILE=)"])
def test_a_folder_swapped_between_check_and_open_is_caught_by_what_was_opened(tmp_path,
                                                                               monkeypatch, kind):
    """The race made deterministic: real/ is swapped for a link to outside/ right after
    the name was checked.  What was opened is outside, so it is refused; reading it again by
    name (the old way) loaded R_OUTSIDE or quoted a cell of outside/secret.csv."""
    from pneunet.netlist.includes import IncludePolicy

    home, outside, top = _swap_setup(tmp_path)
    resolve = IncludePolicy.resolve

    def resolve_then_swap(self, item, base):
        path = resolve(self, item, base)
        if item.text.endswith(".pn" if kind == ".include" else ".csv"):
            _swap(home, outside)
        return path

    monkeypatch.setattr(IncludePolicy, "resolve", resolve_then_swap)
    with pytest.raises(NetlistError, match="changed while it was opened and now leads "
                                           "outside|cannot open included") as info:
        parse_file(top)
    assert "777" not in info.value.report()


def test_a_folder_swapped_for_a_link_in_a_loop_never_leads_outside(tmp_path):
    """A thread swaps real/ for a symbolic link to outside/ and back, as fast as it can,
    while the netlist is read 100 times (and on, up to 20 s, until one read gets through: on
    a loaded machine a read can overlap a swap 100 times running): each read gets the
    inside files or is refused."""
    import threading
    import time

    home, outside, top = _swap_setup(tmp_path)
    stop = threading.Event()

    def swapper():
        while not stop.is_set():
            _swap(home, outside)
            time.sleep(0.0005)
            _unswap(home)
            time.sleep(0.001)

    thread = threading.Thread(target=swapper, daemon=True)
    thread.start()
    try:
        outcomes, deadline = [], time.monotonic() + 20.0
        while len(outcomes) < 100 or ("inside" not in outcomes and time.monotonic() < deadline):
            outcomes.append(_outcome(top))
    finally:
        stop.set()
        thread.join()
    assert set(outcomes) <= {"inside", "refused"} and "inside" in outcomes
