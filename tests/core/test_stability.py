"""``.op()`` says whether the circuit settles at its operating point (issue 16, done-when 4)."""
import numpy as np

from pneunet.paper_circuits import oscillator


def test_the_papers_oscillator_will_not_settle_at_its_operating_point():
    op = oscillator().op()
    assert op.stability.stable is False
    assert op.stability.slowest.real > 0.1  # 1/s: the deviation grows within seconds
    assert "UNSTABLE" in str(op) and "will not settle" in str(op)
    assert repr(op.stability) == ("<Stability UNSTABLE: modes 1, slowest eigenvalue +1.19 1/s; "
                                  ".describe(), .eigenvalues, .slowest>")


def test_with_r_out_zero_it_settles_at_the_rate_the_transient_decays():
    circuit = oscillator(0.0)
    op = circuit.op()
    assert op.stability.stable is True and "stable" in str(op)
    assert all(v.real < 0 for v in op.stability.eigenvalues)
    # the late transient approaches the operating point as exp(λ t)
    sol = circuit.tran(12.0, t_step=0.05)
    gap = np.abs(sol.pressure("tank") - op.pressures["tank"])
    late = (sol.t > 6) & (gap > 1e-3)
    rate = np.polyfit(sol.t[late], np.log(gap[late]), 1)[0]
    assert abs(rate - op.stability.slowest.real) < 0.05 * abs(rate)
