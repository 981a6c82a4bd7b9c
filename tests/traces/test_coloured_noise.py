"""A record whose measurement noise is coloured (a logger or sensor that filters: AR(1)
noise, coefficient 0.7, at 50 Hz) makes a right model look wrong, since the noise floor
assumes white noise (docs/diagnose.md, "Limits"): its `unexplained` verdict says so in a
note, and a white-noise record that a model misses (a leak the netlist lacks) gets no
such note.  Two tanks driven by a supply sine (stand-alone generator,
:mod:`.standalone_tanks`), the AR(1) noise written out here; no candidates offered and
the start read from the record, so each diagnosis is one fit."""
import numpy as np
import pytest

from pneunet.netlist.builder import NetlistBuilder
from pneunet.truth.circuits import diagnose_trace

from .standalone_tanks import TRUTH, sine_supply, tanks_record


def _ar1(n, phi, sigma, rng):
    w = rng.standard_normal(n + 200)
    e = np.zeros_like(w)
    for i in range(1, len(w)):
        e[i] = phi * e[i - 1] + np.sqrt(1.0 - phi ** 2) * w[i]
    return sigma * e[200:]


@pytest.mark.parametrize("phi, leak, noted", [(0.7, None, True), (0.0, 5.0, False)],
                         ids=["coloured-clean", "white-leak"])
def test_an_unexplained_record_with_coloured_noise_says_so(phi, leak, noted):
    rec = tanks_record(start=17.3, seconds=36.0, dt=0.02, noise=0.0, seed=1,
                       source=sine_supply, **({"leak": leak} if leak else {}))
    rng = np.random.default_rng(7)
    for column in ("p_t1_kPa", "p_t2_kPa"):
        rec[column] += _ar1(len(rec), phi, 0.35, rng)
    d = diagnose_trace(NetlistBuilder("netlists/two_tanks_sine.pn"), rec,
                       {"R1": (0.7, 0.05, 5.0), "R2": (1.5, 0.1, 20.0)},
                       fixed={"V1": TRUTH["V1"], "V2": TRUTH["V2"]}, node="t2", effects=[],
                       start_state="record")
    assert d.verdict == "unexplained", d.report()
    said = [n for n in d.notes if "correlated from sample to sample" in n]
    assert bool(said) == noted, d.notes
    correlation = d.to_json()["noise"]["second_difference_correlation"]
    if noted:  # AR(1) of 0.7: −0.52 by its formula; white noise −2/3
        assert "p_t1" in said[0] and "p_t2" in said[0]
        assert all(-0.58 < c < -0.46 for c in correlation.values()), correlation
    else:
        assert all(abs(c + 2 / 3) < 0.1 for c in correlation.values()), correlation
