"""A fit that stops on its simulation budget says so: its estimates and intervals are
where it stopped, not at the best fit (before, `fit-trace` printed them like a converged
fit's: the inverter chain from R_pull 40, R_pull 11.7 [8.1, 17.0] for a true 23)."""
from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits import fit_trace

from .standalone_inverter import inverter_record

CHAIN = "netlists/inverter.pn"


def _fit(guess, max_nfev):
    rec = inverter_record(0.5, 6.0, dt=0.02, noise=0.3, seed=1, Rpull=23.0)
    return fit_trace(NetlistBuilder(CHAIN), rec, {"Rpull": (guess, 2.0, 200.0)},
                     node="out1", max_nfev=max_nfev)


def test_a_fit_stopped_on_its_budget_warns_in_its_report():
    fit = _fit(60.0, 3)
    assert not fit.success
    assert "stopped on its budget" in fit.unconverged()
    assert f"warning: {fit.unconverged()}" in fit.report()
    assert "--max-nfev" in fit.report()
    assert fit.stopped_on_budget() and fit.as_dict()["stopped_on_budget"] is True


def test_a_converged_fit_has_no_warning():
    fit = _fit(23.0, 40)
    assert fit.success and fit.unconverged() == ""
    assert "warning" not in fit.report()
    assert fit.as_dict()["stopped_on_budget"] is False
    assert abs(fit.values["Rpull"] - 23.0) < 0.5
