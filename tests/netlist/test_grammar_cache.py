"""The netlist parser's LALR tables are built once per user, not once per process: lark
keeps them in the user's private cache folder and rebuilds them when the file is
damaged; a folder others could write to is never read (the file is a pickle)."""
import os
import stat

from pneunet.netlist import syntax

TEXT = ".param R=2\nPH supply 496kPa\nR1 supply tank {R}kPa*s/mg\nV1 tank 100mL\n"


def build():
    return syntax.lark_parser.__wrapped__()  # past the per-process lru_cache


def test_tables_are_kept_in_the_users_private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    path = tmp_path / "pneunet" / "netlist-grammar.lark-cache"
    assert syntax.grammar_cache() == str(path)
    assert stat.S_IMODE(os.stat(path.parent).st_mode) == 0o700
    built = build()
    assert hasattr(built, "grammar") and path.stat().st_size > 1000  # built, then written
    loaded = build()
    assert not hasattr(loaded, "grammar")  # lark loaded the tables: no grammar analysed
    assert loaded.parse(TEXT, start="netlist") == built.parse(TEXT, start="netlist")
    path.write_bytes(b"damaged\n")  # a torn write: rebuilt, silently, and written again
    again = build()
    assert hasattr(again, "grammar") and path.stat().st_size > 1000
    assert again.parse(TEXT, start="netlist") == built.parse(TEXT, start="netlist")


def test_a_folder_others_can_write_is_not_used(tmp_path, monkeypatch):
    folder = tmp_path / "pneunet"
    folder.mkdir()
    folder.chmod(0o777)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert syntax.grammar_cache() is False
    assert hasattr(build(), "grammar") and list(folder.iterdir()) == []


def test_a_cache_that_cannot_be_made_still_parses(tmp_path, monkeypatch, capfd):
    """XDG_CACHE_HOME on a file: no cache, no message, the netlist is read."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    assert syntax.grammar_cache() is False
    parser = build()  # the parser as a process without a cache builds it
    assert parser.parse(TEXT, start="netlist") == \
        syntax.lark_parser().parse(TEXT, start="netlist")
    assert capfd.readouterr() == ("", "")
