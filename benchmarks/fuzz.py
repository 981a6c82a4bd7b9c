"""Mutation fuzzing of pneunet's input readers (issue 17).

    python benchmarks/fuzz.py --minutes 30 [--target netlist|csv|all] [--seed 0] [--save DIR]

Each case takes a valid input of a target (the shipped netlists for ``netlist``, the
sample data files of examples/data for ``csv``), applies one to three random mutations
(netlists: delete, duplicate or swap tokens and lines, random bytes, huge and tiny
numbers, deep nesting, hostile includes, truncation; CSV: delete, duplicate, swap or
replace cells and rows, separators, encodings, random bytes, huge numbers, truncation)
and reads the result the way the command line does.  Every case must end as ``ok`` (read and validated) or
``located`` (a PneunetError naming a place); the counts of ``unlocated`` errors,
``crash`` (any other exception), ``hang`` (over --timeout seconds) and ``escape`` (a file
opened outside the case's folder) must stay zero.  Failing cases are written to --save.

A target is a :class:`Target` in :data:`TARGETS` (``register``): its seed inputs, the
file suffix, the function that reads one file and its mutations.  tests/netlist/test_fuzz.py
and tests/identify/test_fuzz_csv.py run the same mutations under hypothesis with a small
fixed budget.
"""
from __future__ import annotations

import argparse
import os
import random
import re
import signal
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
OUTCOMES = ("ok", "located", "unlocated", "crash", "hang", "escape")


@dataclass
class Target:
    """What to fuzz: seed inputs (bytes), the suffix of a case file, and ``read(path)``,
    which returns normally or raises a PneunetError."""

    name: str
    seeds: Callable[[], list]
    read: Callable[[Path], None]
    suffix: str
    mutate: Callable | None = None  # (data, rng, rounds) -> data; default :func:`mutate`

    def mutated(self, data: bytes, rng, rounds: int | None = None) -> bytes:
        return (self.mutate or mutate)(data, rng, rounds)


TARGETS: dict[str, Target] = {}


def register(target: Target) -> Target:
    TARGETS[target.name] = target
    return target


# -- the netlist target ---------------------------------------------------------------------
def _netlist_seeds() -> list:
    return [p.read_bytes() for p in sorted((ROOT / "netlists").glob("*.pn"))]


def _read_netlist(path: Path) -> None:
    from pneunet.netlist import parse_file

    parse_file(path).validate()


register(Target("netlist", _netlist_seeds, _read_netlist, ".pn"))


# -- mutations -------------------------------------------------------------------------------
SPECIAL = ["1e999999", "-1e400", "1e-400", "1e-300mL", "nan", "inf", "-inf", "0", "-1", "{",
           "}", "(", ")", "=", '"', "+", "*", ";", "[0:1e12]", "R[0:-5]", "Rl[0:3][0:3]",
           "[0.5:3.5]", "{1/0}", "{x}", "200kPa", "250 mL", "mL", "p(", "X1.pclose", "\t",
           ".subckt", ".ends", ".param", ".include", ".step param R 1 1e9 1", ".tran 1e-9 1e9",
           "\u00e9", "\ufeff", "\x00", "0x10", "1_000", "١٢", "9" * 400, "PULSE(1 2)",
           "(1 2)", "k=v", "p(tank)", '"text"', "VALVE(axi)", "a=b=c", "x" * 3000,
           "{" + "x" * 3000 + "}", "R=(1)"]
HOSTILE_LINES = ['.include "/etc/passwd"', '.include "../../../../../../etc/hostname"',
                 '.include "/proc/self/environ"', '.include "/dev/zero"', '.include "."',
                 '.include "' + "a" * 5000 + '"', '.lib "/etc/passwd"', ".include ~/.bashrc"]
_TOKEN = re.compile(r"\S+|\s+")


def _tokens(text):
    return _TOKEN.findall(text)


def _word_positions(tokens):
    return [i for i, t in enumerate(tokens) if not t.isspace()] or [0]


def m_delete_token(text, rng):
    tokens = _tokens(text)
    if tokens:
        del tokens[rng.choice(_word_positions(tokens))]
    return "".join(tokens)


def m_duplicate_token(text, rng):
    tokens = _tokens(text)
    if tokens:
        i = rng.choice(_word_positions(tokens))
        tokens.insert(i, tokens[i] + " ")
    return "".join(tokens)


def m_swap_tokens(text, rng):
    tokens = _tokens(text)
    words = _word_positions(tokens)
    if len(words) > 1:
        i, j = rng.sample(words, 2)
        tokens[i], tokens[j] = tokens[j], tokens[i]
    return "".join(tokens)


def m_special_token(text, rng):
    tokens = _tokens(text)
    if tokens:
        tokens[rng.choice(_word_positions(tokens))] = rng.choice(SPECIAL)
    return "".join(tokens)


def m_huge_number(text, rng):
    """Replace a number's digits or exponent by an extreme one."""
    numbers = list(re.finditer(r"\d+(?:\.\d*)?(?:[eE][-+]?\d+)?", text))
    if not numbers:
        return text
    m = rng.choice(numbers)
    value = rng.choice(["1e308", "1e309", "1e-320", "1e-400", "9" * rng.randint(20, 400),
                        "1e" + str(rng.randint(-99999, 99999)), "0", "0.0"])
    return text[:m.start()] + value + text[m.end():]


def m_deep_nesting(text, rng):
    """An expression, a unary chain or a subcircuit chain nested very deep."""
    depth = rng.choice([50, 300, 1000, 5000])
    kind = rng.choice(["parens", "unary", "ternary", "power", "subckt"])
    if kind == "subckt":
        n = min(depth, 300)
        lines = [f".subckt S{i} a\nXs a S{i + 1}\n.ends" for i in range(n)]
        return text + "\n" + "\n".join(lines) + f"\n.subckt S{n} a\nR1 a atm 1\n.ends\nXtop x S0\n"
    expr = {"parens": "(" * depth + "1" + ")" * depth, "unary": "-" * depth + "1",
            "ternary": "1?" * depth + "1" + ":1" * depth, "power": "1" + "^1" * depth}[kind]
    return text + f"\n.param deep={{{expr}}}\n"


def m_line(text, rng):
    """Delete, duplicate or swap lines, or add a hostile include."""
    lines = text.split("\n")
    op = rng.choice(["delete", "duplicate", "swap", "include"])
    i = rng.randrange(len(lines))
    if op == "delete":
        del lines[i]
    elif op == "duplicate":
        lines.insert(i, lines[i])
    elif op == "swap":
        j = rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    else:
        lines.insert(i, rng.choice(HOSTILE_LINES))
    return "\n".join(lines)


def m_truncate(text, rng):
    return text[:rng.randrange(len(text) + 1)]


TEXT_MUTATIONS = [m_delete_token, m_duplicate_token, m_swap_tokens, m_special_token,
                  m_huge_number, m_deep_nesting, m_line, m_truncate]


def m_random_bytes(data: bytes, rng) -> bytes:
    """Overwrite or insert a few random bytes (invalid UTF-8 included)."""
    data = bytearray(data)
    for _ in range(rng.randint(1, 8)):
        pos = rng.randrange(len(data) + 1)
        byte = rng.randrange(256)
        if rng.random() < 0.5 and pos < len(data):
            data[pos] = byte
        else:
            data.insert(pos, byte)
    return bytes(data)


def mutate(data: bytes, rng: random.Random, rounds: int | None = None) -> bytes:
    """``data`` after one to three random mutations."""
    for _ in range(rounds or rng.randint(1, 3)):
        if rng.random() < 0.15:
            data = m_random_bytes(data, rng)
            continue
        text = data.decode("utf-8", errors="surrogateescape")
        text = rng.choice(TEXT_MUTATIONS)(text, rng)
        data = text.encode("utf-8", errors="surrogateescape")
    return data


# -- the csv target: measured data as fit, diagnose and fit-trace read it ---------------------
def _csv_seeds() -> list:
    """The sample bench file and recording, cut to their first rows (fast cases).  Each
    is read once here: pandas reads the CPU quota under /sys on its first CSV, which is
    no case's doing."""
    out = []
    for name, rows in (("bench_axi.csv", 80), ("oscillator_rec.csv", 120)):
        lines = (ROOT / "examples" / "data" / name).read_bytes().split(b"\n")
        out.append(b"\n".join(lines[:3 + rows]) + b"\n")
    with tempfile.TemporaryDirectory() as tmp:
        for data in out:
            (Path(tmp) / "seed.csv").write_bytes(data)
            try:
                _read_csv(Path(tmp) / "seed.csv")
            except Exception:  # noqa: BLE001 - only warming up
                pass
    return out


def _read_csv(path: Path) -> None:
    """Read ``path`` as bench data (``fit``, ``diagnose``) and as a recording
    (``fit-trace``): ok when one reader accepts it and the other fails with a location;
    else its unlocated error first, or the first error."""
    from pneunet.common.errors import PneunetError
    from pneunet.truth.valves.identify import load_measurements
    from pneunet.truth.circuits.data import read_trace

    errors = []
    for read in (load_measurements, read_trace):
        try:
            read(path, max_rows=1000)
        except PneunetError as err:
            errors.append(err)
    errors.sort(key=lambda e: bool(e.where or e.span))
    if errors and (len(errors) == 2 or not (errors[0].where or errors[0].span)):
        raise errors[0]


CELLS = ["", "nan", "NaN", "inf", "-inf", "Infinity", "1e308", "-1e308", "1e309", "1e-320",
         "0", "-5", "abc", "1.2.3", "12,5", '"1"', '"a,b"', "NA", "n/a", "None", "\u00e9",
         "\u0661\u0662", "9" * 400, " 1", "1 ", "0x10", "1_000", "1e5kPa", "#", "\t", "\x00"]
HEADERS = ["p_tank_bar", "p_tank_kpa", "p_in_bar", "p_in_kPag", "p_x_mg_s", "mdot_R1_kPa",
           "time_ms", "t", "", "p_in_kPa", "time_s", "mdot_mg_s", "p_tank", "sweep", "valve"]


def _rows(text):
    lines = text.split("\n")
    body = [i for i, line in enumerate(lines) if line and not line.startswith("#")]
    return lines, body or [0]


def c_cells(text, rng):
    """Delete, duplicate, swap or replace a cell (a header cell included)."""
    lines, body = _rows(text)
    i = rng.choice(body)
    cells = lines[i].split(",")
    k = rng.randrange(len(cells))
    op = rng.choice(["delete", "duplicate", "swap", "special", "special", "header"])
    if op == "delete" and len(cells) > 1:
        del cells[k]
    elif op == "duplicate":
        cells.insert(k, cells[k])
    elif op == "swap":
        j = rng.choice(body)
        other = lines[j].split(",")
        m = rng.randrange(len(other))
        cells[k], other[m] = other[m], cells[k]
        if j != i:
            lines[j] = ",".join(other)
    elif op == "header":
        i, cells = body[0], lines[body[0]].split(",")
        cells[rng.randrange(len(cells))] = rng.choice(HEADERS)
    else:
        cells[k] = rng.choice(CELLS)
    lines[i] = ",".join(cells)
    return "\n".join(lines)


def c_rows(text, rng):
    """Delete, duplicate or swap data rows, reverse or shuffle them, drop all of them."""
    lines, body = _rows(text)
    op = rng.choice(["delete", "duplicate", "swap", "reverse", "shuffle", "empty"])
    data = body[1:] or body
    i, j = rng.choice(data), rng.choice(data)
    if op == "delete":
        del lines[i]
    elif op == "duplicate":
        lines.insert(i, lines[i])
    elif op == "swap":
        lines[i], lines[j] = lines[j], lines[i]
    else:
        rows = [lines[k] for k in data]
        rows = ([] if op == "empty" else rows[::-1] if op == "reverse"
                else rng.sample(rows, len(rows)))
        lines = [line for k, line in enumerate(lines) if k not in set(data)] + rows
    return "\n".join(lines)


def c_separator(text, rng):
    """Another separator or decimal mark, CRLF line ends, or blank and comment lines."""
    op = rng.choice(["semicolon", "tab", "decimal", "crlf", "blank"])
    if op == "semicolon":
        return text.replace(",", ";")
    if op == "tab":
        return text.replace(",", "\t")
    if op == "decimal":
        return text.replace(".", ",")
    if op == "crlf":
        return text.replace("\n", "\r\n")
    lines = text.split("\n")
    lines.insert(rng.randrange(len(lines) + 1), rng.choice(["", "   ", "# note", ",,,"]))
    return "\n".join(lines)


CSV_MUTATIONS = [c_cells, c_cells, c_rows, c_separator, m_huge_number, m_truncate]


def mutate_csv(data: bytes, rng: random.Random, rounds: int | None = None) -> bytes:
    """``data`` after one to three CSV mutations (cells, rows, separators, numbers,
    truncation), random bytes, or another encoding (Latin-1, UTF-16, a BOM)."""
    for _ in range(rounds or rng.randint(1, 3)):
        roll = rng.random()
        if roll < 0.1:
            data = m_random_bytes(data, rng)
            continue
        text = data.decode("utf-8", errors="surrogateescape")
        if roll < 0.2:
            encoding = rng.choice(["latin-1", "utf-16", "utf-8-sig", "cp1252"])
            data = text.replace("# ", "# mesur\u00e9 ", 1).encode(encoding, errors="replace")
            continue
        text = rng.choice(CSV_MUTATIONS)(text, rng)
        data = text.encode("utf-8", errors="surrogateescape")
    return data


register(Target("csv", _csv_seeds, _read_csv, ".csv", mutate_csv))


# -- running one case ------------------------------------------------------------------------
class _Hang(Exception):
    pass


def _alarm(signum, frame):
    raise _Hang()


_OPENED: list = []
_WATCH: list = []


def _audit(event, args):
    """Record files opened while reading a case, except by imports (a library importing
    itself may read /proc; the reader must not)."""
    if _WATCH and event == "open" and args and isinstance(args[0], (str, bytes, os.PathLike)):
        frame = sys._getframe(1)
        while frame is not None:
            if "importlib" in frame.f_code.co_filename:  # imports, entry points
                return
            frame = frame.f_back
        _OPENED.append(os.path.realpath(os.fsdecode(args[0])))


def watch_opens() -> None:
    """Install the audit hook that :func:`run_case` reads (once per process)."""
    if not _WATCH_INSTALLED:
        sys.addaudithook(_audit)
        _WATCH_INSTALLED.append(True)


_WATCH_INSTALLED: list = []


def _code_folders():
    import pneunet

    return tuple(os.path.realpath(p) + os.sep for p in
                 {sys.prefix, sys.base_prefix, os.path.dirname(pneunet.__file__),
                  *(p for p in sys.path if p and os.path.isdir(p))})


def run_case(target: Target, data: bytes, folder: Path, timeout: float = 10.0):
    """(outcome, detail) of reading ``data`` as a file of ``target`` in ``folder``."""
    from pneunet.common.errors import PneunetError

    path = folder / f"case{target.suffix}"
    path.write_bytes(data)
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    _OPENED.clear()
    _WATCH.append(True)
    start = time.perf_counter()
    try:
        target.read(path)
        outcome, detail = "ok", ""
    except _Hang:
        outcome, detail = "hang", f"over {timeout:g} s"
    except PneunetError as err:
        located = err.span is not None or bool(err.where)
        outcome, detail = ("located" if located else "unlocated"), str(err)[:300]
    except RecursionError as err:  # pragma: no cover - reported, never expected
        outcome, detail = "crash", f"RecursionError: {err}"[:300]
    except Exception as err:  # noqa: BLE001 - a crash is what we count
        outcome, detail = "crash", f"{type(err).__name__}: {err}"[:300]
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
        _WATCH.clear()
    if outcome != "hang" and time.perf_counter() - start > timeout:
        outcome, detail = "hang", f"{time.perf_counter() - start:.1f} s"
    home = os.path.realpath(folder) + os.sep
    code = _code_folders()
    outside = [p for p in _OPENED if not p.startswith(home) and not p.startswith(code)]
    if outside:
        outcome, detail = "escape", "opened " + ", ".join(outside[:3])
    return outcome, detail


def fuzz(targets, seconds: float, seed: int = 0, timeout: float = 10.0, save: Path | None = None,
         progress=print) -> dict:
    """Run cases round-robin over ``targets`` for ``seconds``; the counts per outcome."""
    watch_opens()
    rng = random.Random(seed)
    counts = {t.name: dict.fromkeys(("cases",) + OUTCOMES, 0) for t in targets}
    seeds = {t.name: t.seeds() for t in targets}
    end = time.monotonic() + seconds
    next_report = time.monotonic() + 60
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        while time.monotonic() < end:
            for target in targets:
                data = target.mutated(rng.choice(seeds[target.name]), rng)
                outcome, detail = run_case(target, data, folder, timeout)
                c = counts[target.name]
                c["cases"] += 1
                c[outcome] += 1
                if outcome not in ("ok", "located"):
                    progress(f"{target.name} case {c['cases']}: {outcome}: {detail}")
                    if save is not None:
                        save.mkdir(parents=True, exist_ok=True)
                        (save / f"{target.name}_{outcome}_{c['cases']}{target.suffix}") \
                            .write_bytes(data)
            if time.monotonic() > next_report:
                next_report += 60
                progress(_summary(counts))
    return counts


def _summary(counts) -> str:
    return "; ".join(f"{name}: " + ", ".join(f"{k} {v}" for k, v in c.items())
                     for name, c in counts.items())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=1.0)
    parser.add_argument("--target", default="netlist", choices=[*TARGETS, "all"])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds before a hang")
    parser.add_argument("--save", type=Path, default=None, help="folder for failing cases")
    args = parser.parse_args(argv)
    targets = list(TARGETS.values()) if args.target == "all" else [TARGETS[args.target]]
    start = time.monotonic()
    counts = fuzz(targets, args.minutes * 60, args.seed, args.timeout, args.save)
    print(f"{time.monotonic() - start:.0f} s, seed {args.seed}: {_summary(counts)}")
    bad = sum(c[k] for c in counts.values() for k in OUTCOMES[2:])
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
