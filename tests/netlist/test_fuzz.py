"""Mutated shipped netlists (benchmarks/fuzz.py's mutations, driven by hypothesis with a
fixed budget) are read and validated, or fail with a located PneunetError: never a crash,
a hang or a file opened outside the netlist's folder.  Parse and validate only."""
import random
import sys
from pathlib import Path

from hypothesis import HealthCheck, given, settings, strategies as st

sys.path.insert(0, str(Path(__file__).parents[2] / "benchmarks"))
import fuzz  # noqa: E402

TARGET = fuzz.TARGETS["netlist"]
SEEDS = TARGET.seeds()
fuzz.watch_opens()


@settings(max_examples=200, derandomize=True, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(index=st.integers(0, len(SEEDS) - 1), seed=st.integers(0, 2**32 - 1),
       rounds=st.integers(1, 3))
def test_a_mutated_netlist_is_read_or_fails_with_a_location(tmp_path_factory, index, seed, rounds):
    data = fuzz.mutate(SEEDS[index], random.Random(seed), rounds)
    folder = tmp_path_factory.mktemp("case")
    outcome, detail = fuzz.run_case(TARGET, data, folder, timeout=20)
    assert outcome in ("ok", "located"), (outcome, detail, data[:2000])


WORDS = st.sampled_from(["P1", "R1", "V1", "X1", "Xc[0:3]", "A1", "F1", "a", "b", "tank", "atm", "0",
                         "gnd", "n[0:3]", "200kPa", "1e999", "-1", "0", "1e-300mL", "10mL",
                         "{Rf*2}", "{1/0}", "{x}", "axi", "CELL", "R=1", "V=2mL", "pclose=90kPa",
                         "PULSE(1 2 3)", "PWL(0 1 1 2)", "VALVE(axi)", "p(a)", "mdot(R1)",
                         "(", ")", "=", '"v.pn"', "list", "param", "Rf", "x", "FIND", "AT=1s"])
HEADS = st.sampled_from([".param", ".subckt", ".ends", ".include", ".lib", ".model", ".ic",
                         ".options", ".tran", ".op", ".dc", ".step", ".meas", ".save", ".end",
                         "P1", "R1", "V1", "X1", "A1", "valve", "*", "+", ";"])
LINES = st.builds(lambda head, words: " ".join([head, *words]), HEADS,
                  st.lists(WORDS, max_size=8))


@settings(max_examples=300, derandomize=True, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(lines=st.lists(LINES, min_size=1, max_size=12))
def test_a_netlist_made_of_grammar_pieces_is_read_or_fails_with_a_location(tmp_path_factory,
                                                                          lines):
    data = ("\n".join(lines) + "\n").encode()
    outcome, detail = fuzz.run_case(TARGET, data, tmp_path_factory.mktemp("case"), timeout=20)
    assert outcome in ("ok", "located"), (outcome, detail, data[:2000])
