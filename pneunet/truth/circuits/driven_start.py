"""Which start of a record of a circuit driven by its sources fits it better.

A driven record that starts off the rest state, after its sources began to change, is
fitted from its first samples and from the netlist's rest state driven by its sources up
to the first sample (:func:`better_start`); where periodic sources place the first sample
only within a period, the rest start is fitted again at the netlist time the record
shows at the fitted values (:func:`clock_at_fit`).  Fits are
:class:`~pneunet.truth.circuits.fit.TraceFit`.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...common.errors import PneunetError
from .initial_state import P0_PREFIX, choose_start


def _rms_on_common(*fits) -> list[float]:
    """Each fit's rms (its unit) on the samples every one of ``fits`` compares."""
    both = np.logical_and.reduce([np.isfinite(f.scaled_residuals()) for f in fits])
    return [float(np.sqrt(np.mean(f.scaled_residuals()[both] ** 2))) for f in fits]


#: a start from the record's first samples is kept over the netlist's rest state driven
#: up to them only where its rms is below this fraction of the other's
RECORD_START_GAIN = 0.9


def better_start(rest, record):
    """Of one record's fits from the netlist's rest state driven by its sources up to the
    first sample and from the first samples, the first unless the second's rms, on the
    samples both compare, is below :data:`RECORD_START_GAIN` × its: the history carries
    what the first samples do not show (a gas temperature, a dead volume's pressure),
    and every effect fitted later starts from the same state.  A tanks' record from 0.7 s
    into a charge, with heat exchange hidden: from the record 0.733 kPa, from rest 0.743;
    from the record no effect reached the floor (its gas starting at wall temperature),
    from rest heat exchange did.  The start's reason says so; the simulations of both
    count."""
    rms = _rms_on_common(rest, record)
    best = record if rms[1] < RECORD_START_GAIN * rms[0] else rest
    state = replace(best.start_state, reason=(
        f"{best.start_state.reason}; fitted from both starts, rms on the samples both "
        f"compare: from rest {rms[0]:.4g}, from the record {rms[1]:.4g} {best.unit}"))
    total = rest.nfev + record.nfev
    return replace(best, nfev=total, extras={**best.extras, "start_state": state,
                                              "simulations": total})


def clock_at_fit(fit, model, df, where: str, refit):
    """``fit`` (from the netlist's rest state driven by its sources to the first sample,
    at the netlist time the record showed at the parameter guesses) or, where the record
    shows another netlist time at the fitted values — periodic sources place it only
    within a period: their first period after switch-on or a settled one —
    ``refit(state, values)`` from the rest state there, whichever fits the samples both
    compare better.  Two tanks driven by a square wave, recorded from 15 s: at the
    guesses (R 40 % and 25 % off) the first period and a settled one misfit alike and
    the first was taken; fitted from it, 2.2× the floor on the fitted window, and the
    clean record was called ``unexplained``."""
    old = fit.start_state
    if not old.clock_period:
        return fit
    try:  # a start that cannot be found or fitted there leaves ``fit`` as it is
        state = choose_start(model, {k: v for k, v in fit.values.items()
                                     if not k.startswith(P0_PREFIX)}, df, "rest", None, where)
        if state.settle <= 0 or \
                abs(state.first_time - old.first_time) < 0.5 * old.clock_period:
            return fit
        other = refit(replace(state, reason=(
            "the netlist's rest state driven by its sources to the first sample, at the "
            "netlist time the record shows at the fitted values")), dict(fit.values))
    except PneunetError:
        return fit
    rms_fit, rms_other = _rms_on_common(fit, other)
    better = other if rms_other < rms_fit else fit
    total = fit.nfev + other.nfev
    return replace(better, nfev=total, extras={**better.extras, "simulations": total})
