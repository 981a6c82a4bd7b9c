"""Shared bench data and fits (session scope: each fit once per test run)."""
import pytest

from pneunet.truth.valves.identify import fit_valve, simulate_bench
from pneunet.physics.valve_params import PAPER_VALVES

#: bench seed of the single-dataset tests (outputs, figures, CLI).  No test checks
#: interval coverage on it: the round-trip tests fit the first ROUND_TRIP_SEEDS
#: seeds and count (see test_fit.py and benchmarks/coverage_fit.py).
SEED = 6
#: seeds 0..N-1 of the round-trip tests (the first N, not chosen)
ROUND_TRIP_SEEDS = 6


@pytest.fixture(scope="session")
def bench():
    cache = {}

    def get(name, **options):
        key = (name, tuple(sorted(options.items())))
        if key not in cache:
            options.setdefault("seed", SEED)
            cache[key] = simulate_bench(PAPER_VALVES[name], **options)
        return cache[key]

    return get


@pytest.fixture(scope="session")
def fitted(bench):
    cache = {}

    def get(name, **options):
        key = (name, tuple(sorted(options.items())))
        if key not in cache:
            cache[key] = fit_valve(bench(name), **options)
        return cache[key]

    return get


@pytest.fixture(scope="session")
def round_trips():
    """fits[(name, seed)] of bench seeds 0..ROUND_TRIP_SEEDS-1 (``options`` to fit_valve)."""
    cache = {}

    def get(name, **options):
        key = (name, tuple(sorted(options.items())))
        if key not in cache:
            cache[key] = {seed: fit_valve(simulate_bench(PAPER_VALVES[name], seed=seed), **options)
                          for seed in range(ROUND_TRIP_SEEDS)}
        return cache[key]

    return get
