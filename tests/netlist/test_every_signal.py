"""Issue 32: every signal a result holds, every signal an error's hint names and every
signal quantity the docs write is accepted by .save and .meas, and measures the number the
result holds."""
import re
from pathlib import Path

import numpy as np
import pytest

from pneunet.common.errors import NetlistError
from pneunet.netlist import parse_netlist, runner

DOCS = Path(__file__).resolve().parents[2] / "docs"

GAS = (Path(__file__).resolve().parents[1] / "every_kind_gas.pn").read_text()
LIQUID = """.options fluid=water
P1 pump 3bar
orifice O1 pump act 0.5mm
accumulator A1 act 20mL 0.05mL/kPa
laminar_tube T1 act atm length=1m diameter=1mm
"""


@pytest.fixture(scope="module", params=[GAS, LIQUID], ids=["gas", "liquid"])
def circuit(request):
    deck = parse_netlist(request.param + ".tran 10ms 0.2s\n")
    return request.param, deck.circuit.tran(0.2, t_step=0.01)


def _signals(sol):
    """(quantity, target) of every signal of the result but node pressures."""
    out = []
    for key in sol.signals:
        quantity, _, target = key.partition("_")
        if quantity != "p":
            out.append((quantity, target))
    return out


def test_every_signal_of_a_result_is_accepted_and_measured(circuit):
    text, sol = circuit
    signals = _signals(sol)
    assert len(signals) >= (20 if "fluid" not in text else 4)
    saves = " ".join(f"{q}({t})" for q, t in signals)
    meas = "".join(f".meas tran m{i} FIND {q}({t}) AT=0.105\n" for i, (q, t) in enumerate(signals))
    run = runner.run_deck(parse_netlist(text + f".tran 10ms 0.2s\n.save {saves}\n" + meas))
    result = run.results[0][1]
    for i, (q, t) in enumerate(signals):
        expected = np.interp(0.105, result.t, result[f"{q}_{t}"])
        assert run.measures[f"m{i}"] == pytest.approx(expected, rel=1e-9, abs=1e-12), (q, t)


def test_every_signal_a_hint_names_is_accepted(circuit):
    text, sol = circuit
    targets = {t for _, t in _signals(sol)} | {t.split(".s")[0] for _, t in _signals(sol)}
    named = 0
    for target in sorted(targets):
        try:
            parse_netlist(text + f".tran 0.2s\n.save nosuchsignal({target})\n")
        except NetlistError as err:
            assert err.span.line == len(text.splitlines()) + 2   # at the .save line
            for signal in re.findall(r"\w+\([\w.]+\)", err.hint or ""):
                parse_netlist(text + f".tran 0.2s\n.save {signal}\n.meas tran x MAX {signal}\n")
                named += 1
        else:
            pytest.fail(f"nosuchsignal({target}) accepted")
    assert named >= len(targets) - 2   # each element's hint names its signals


def test_a_tube_and_a_pv_actuator_answer_to_their_documented_names():
    run = runner.run_deck(parse_netlist(GAS + ".tran 10ms 0.2s\n.save volume(P2) mdot(L1)\n"
                                        ".meas tran v FIND volume(P2) AT=0.1\n"
                                        ".meas tran q FIND mdot(L1) AT=0.1\n"))
    sol = run.results[0][1]
    assert run.measures["v"] == pytest.approx(np.interp(0.1, sol.t, sol["volume_P2"]))
    assert run.measures["q"] == pytest.approx(np.interp(0.1, sol.t, sol["mdot_L1.s1"]))
    assert 20.0 < run.measures["v"] < 35.0


def test_every_signal_quantity_the_docs_write_is_produced():
    sol = parse_netlist(GAS + ".tran 0.05s\n").circuit.tran(0.05)
    produced = {q for q, _ in _signals(sol)} | {"p", "v", "pressure", "mdot", "m", "i", "flow"}
    written = set()
    for doc in DOCS.glob("*.md"):
        for line in doc.read_text().splitlines():
            if re.match(r"\s*(\.save|\.print|\.meas)", line) or "signal" in line.lower():
                written |= {m for m in re.findall(r"`?\b([A-Za-z]+)\((?:[A-Z]\w*|NAME|node|"
                                                  r"element|TUBE)\)", line)}
    missing = {q for q in written if q not in produced}
    # Re(T1) is a liquid circuit's (checked with the liquid fixture above)
    assert len(written) >= 7 and missing <= {"Re"}, missing
