"""The include policy: files outside the netlist's folder and the search path are refused at
the .include line before they are opened; errors in included files name the include chain."""
import os
from pathlib import Path

import pytest

from pneunet.cli import main
from pneunet.errors import NetlistError
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
