"""Mutated sample data files (benchmarks/fuzz.py's CSV mutations: cells and rows deleted,
duplicated, swapped or replaced, separators, encodings, random bytes, huge numbers,
truncation; driven by hypothesis with a fixed budget) are read as bench data and as a
recording, or fail with a PneunetError naming the file and a column or line: never a
crash, a hang or a file opened outside the case's folder.  Read and validate only."""
import random
import sys
from pathlib import Path

from hypothesis import HealthCheck, given, settings, strategies as st

sys.path.insert(0, str(Path(__file__).parents[2] / "benchmarks"))
import fuzz  # noqa: E402

TARGET = fuzz.TARGETS["csv"]
SEEDS = TARGET.seeds()
fuzz.watch_opens()


@settings(max_examples=400, derandomize=True, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(index=st.integers(0, len(SEEDS) - 1), seed=st.integers(0, 2**32 - 1),
       rounds=st.integers(1, 3))
def test_a_mutated_data_file_is_read_or_fails_with_a_location(tmp_path_factory, index, seed,
                                                              rounds):
    data = TARGET.mutated(SEEDS[index], random.Random(seed), rounds)
    folder = tmp_path_factory.mktemp("case")
    outcome, detail = fuzz.run_case(TARGET, data, folder, timeout=20)
    assert outcome in ("ok", "located"), (outcome, detail, data[:2000])
    if outcome == "located":
        assert str(folder) in detail  # the message names the file
