"""Architecture rules that keep pneunet light and its heavy dependencies contained."""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "pneunet"


def _importers(prefix):
    found = set()
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            if any(n == prefix or n.startswith(prefix + ".") for n in names):
                found.add(path.relative_to(PACKAGE).as_posix())
    return found


@pytest.mark.parametrize("library, allowed", [
    ("matplotlib", {"common/plotting.py"}),
    ("sksundae", {"engine/solvers/sundae.py"}),
    ("scikits", {"engine/solvers/odes.py"}),
])
def test_heavy_library_is_imported_by_one_module(library, allowed):
    assert _importers(library) <= allowed


def test_import_pneunet_stays_light():
    code = ("import sys, pneunet; heavy = [m for m in ('numpy', 'scipy', 'matplotlib', 'sksundae',"
            " 'pandas', 'sklearn', 'pint', 'lark', 'networkx') if m in sys.modules]; print(heavy)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_plain_run_imports_only_what_it_needs(tmp_path):
    """`pneunet run` without --plot writes its CSV without pandas, networkx, scipy.optimize
    or matplotlib (their imports would cost more than a small transient), nor the other
    sub-commands' modules (the fitting's CSV reader, the design code)."""
    netlist = PACKAGE.parent / "netlists" / "oscillator.pn"
    code = ("import sys; from pneunet.interfaces.cli import main; "
            f"status = main(['run', {str(netlist)!r}, '-q', '-o', {str(tmp_path)!r}]); "
            "print(status, 'sksundae.ida' in sys.modules, [m for m in ('pandas', 'networkx', "
            "'scipy.optimize', 'matplotlib', 'pneunet.interfaces.cli.fit', 'pneunet.interfaces.cli.design', "
            "'pneunet.interfaces.cli.fit_trace', 'pneunet.common.csvdata') if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "0 True []"
    header = (tmp_path / "tran.csv").read_text().splitlines()[0]
    assert header.startswith("time_s,") and "p_tank_kPa" in header
