"""A diagnosis of data too small for a noise estimate (24 points) reports the noise
floor as not estimated instead of failing in the report (it was a TypeError)."""
from pneunet.truth.valves.diagnose import diagnose
from pneunet.truth.valves.identify import paper_protocol, simulate_bench
from pneunet.physics.valve_params import PAPER_VALVES


def test_report_without_a_noise_floor():
    data = simulate_bench(PAPER_VALVES["axi"], protocol=paper_protocol(step=150.0), seed=0)
    diag = diagnose(data, progress=False, effects=[], max_effects=0)
    assert diag.to_json()["noise_floor"] is None
    assert "noise floor       = not estimated" in diag.report()
