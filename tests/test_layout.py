"""The layout's import rules (docs/architecture.md), checked on the source: every import
of every module (those inside functions included; ``if TYPE_CHECKING:`` blocks are not
imports), resolved to the module it loads.

* no import circle between modules;
* a stage imports only itself and earlier stages: common → physics → engine → netlist →
  truth → design → interfaces (the package root may import any);
* every module sits in a stage, and every stage's package docstring says what it may
  import.
"""
import ast
import pathlib

import networkx as nx
import pytest

import pneunet

PACKAGE = pathlib.Path(pneunet.__file__).parent
STAGES = ("common", "physics", "engine", "netlist", "truth", "design", "interfaces")


def _name(path: pathlib.Path) -> tuple[str, bool]:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        return ".".join(parts[:-1]), True
    return ".".join(parts), False


MODULES = dict(_name(p) for p in PACKAGE.rglob("*.py"))


def _runtime_nodes(tree):
    """Every node, except those under ``if TYPE_CHECKING:``."""
    todo = [tree]
    while todo:
        node = todo.pop()
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            todo.extend(node.orelse)
            continue
        yield node
        todo.extend(ast.iter_child_nodes(node))


def imports_of(source: str, module: str, is_package: bool) -> set[str]:
    """The pneunet modules ``source`` (module ``module``) imports."""
    out = set()
    for node in _runtime_nodes(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.split(".")[0] == "pneunet")
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".") if is_package else module.split(".")[:-1]
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "pneunet":
                continue
            for a in node.names:  # a submodule imported by name, else its package
                out.add(f"{target}.{a.name}" if f"{target}.{a.name}" in MODULES else target)
    out.discard(module)
    return out


def import_graph() -> nx.DiGraph:
    graph = nx.DiGraph()
    for path in PACKAGE.rglob("*.py"):
        module, is_package = _name(path)
        graph.add_node(module)
        graph.add_edges_from((module, t) for t in imports_of(path.read_text(), module,
                                                            is_package))
    return graph


def stage(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in STAGES else None


def test_no_import_circle():
    circles = [sorted(c) for c in nx.strongly_connected_components(import_graph())
               if len(c) > 1]
    assert not circles, circles


def test_no_import_from_an_earlier_stage_to_a_later_one():
    upward = [(a, b) for a, b in import_graph().edges
              if stage(a) and stage(b) and STAGES.index(stage(b)) > STAGES.index(stage(a))]
    assert not upward, upward


def test_every_module_sits_in_a_stage():
    loose = [m for m in MODULES if stage(m) is None
             and m not in ("pneunet", "pneunet.__main__")]
    assert not loose, loose


@pytest.mark.parametrize("name", STAGES)
def test_each_stage_says_what_it_may_import(name):
    doc = ast.get_docstring(ast.parse((PACKAGE / name / "__init__.py").read_text()))
    assert doc and "May import" in doc, name


def test_the_checks_see_an_upward_import_inside_a_function():
    """The walk itself: a lazy import of the design stage from the engine, and a
    relative one two levels up, resolve to the modules they load."""
    src = "def f():\n    from ...design import sweep\n    from ...common.errors import X\n"
    found = imports_of(src, "pneunet.engine.x.y", False)
    assert found == {"pneunet.design.sweep", "pneunet.common.errors"}
    typing_only = "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import pneunet.design\n"
    assert imports_of(typing_only, "pneunet.engine.x", False) == set()
