"""The README's ``fit``, ``diagnose`` and ``fit-trace`` commands run on the sample files
in ``examples/data/``, and the generator rewrites those files byte for byte."""
import importlib.util
import re
import shlex
from pathlib import Path

import pytest

from pneunet.interfaces.cli import main

ROOT = Path(__file__).resolve().parents[1]
#: options that keep a README command short in the test (same code path, fewer replicates)
FASTER = {"fit": ["--bootstrap", "10"]}


def readme_command(name):
    block = re.search(r"```bash\n(.*?)```", (ROOT / "README.md").read_text().split("## Use it")[1],
                      re.S).group(1)
    lines = [line.split("#")[0].strip() for line in block.splitlines()
             if line.startswith(f"pneunet {name} ")]
    assert len(lines) == 1, f"README: one 'pneunet {name}' command expected"
    return shlex.split(lines[0])[1:]


@pytest.mark.parametrize("name, expect", [
    ("fit", '"model_card": ".model VFIT VALVE('),
    ("diagnose", "verdict           = ADEQUATE"),
    ("fit-trace", "verdict       = ADEQUATE"),
])
def test_readme_command_runs_on_the_sample_files(name, expect, tmp_path, monkeypatch, capsys):
    argv = readme_command(name)
    data = [a for a in argv if a.startswith("examples/data/")]
    assert data and all((ROOT / a).is_file() for a in data), argv
    monkeypatch.chdir(ROOT)
    argv = [str(tmp_path / "figs") if a == "figs/" else a for a in argv]
    assert main(argv + FASTER.get(name, []) + (["--no-progress"] if name != "fit" else [])) == 0
    assert expect in capsys.readouterr().out


def test_sample_files_are_what_the_generator_writes(tmp_path):
    spec = importlib.util.spec_from_file_location("make_samples",
                                                  ROOT / "examples" / "data" / "make_samples.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.main(tmp_path)
    for name in ("bench_axi.csv", "oscillator_rec.csv"):
        assert (tmp_path / name).read_bytes() == (ROOT / "examples" / "data" / name).read_bytes()
