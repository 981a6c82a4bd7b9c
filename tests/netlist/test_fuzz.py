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
