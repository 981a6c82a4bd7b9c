"""A fit's simulation budget counts this process' CPU time, not the clock: on a machine
busy with other work (a test suite's other workers, a second diagnosis) a simulation
takes longer by the clock, and a budget by the clock failed the right candidate of a
study at every screening point."""
import time

import pytest

from pneunet.common.errors import SolverError
from pneunet.truth.circuits.model import cpu_time_budget


def test_waiting_is_not_spending():
    start = time.perf_counter()
    with cpu_time_budget(0.2):
        time.sleep(0.5)  # the clock runs, the CPU does not
    assert time.perf_counter() - start >= 0.5


def test_computing_past_the_budget_stops_with_a_solver_error():
    start = time.process_time()
    with pytest.raises(SolverError, match="its budget"):
        with cpu_time_budget(0.2):
            while time.process_time() - start < 5.0:
                sum(range(1000))
    assert time.process_time() - start < 1.0
