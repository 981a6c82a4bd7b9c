import pytest


@pytest.fixture(scope="session")
def paper_cycle():
    """The paper's oscillator (R_out = 2 R_f) simulated until its cycle converges."""
    from pneunet.design.circuits import oscillator
    from pneunet.engine.oscillation import oscillator_period

    return oscillator_period(oscillator(), "tank", rtol=1e-4)
