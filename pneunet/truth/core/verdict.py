"""The verdict of a diagnosis: never a forced choice.

* ``adequate``: the base model's held-out error is already at the noise floor
  (within ``tolerance`` × floor) and no candidate takes it clearly lower (below
  :data:`NEAR_FLOOR` × floor, by :data:`NEAR_GAIN`; looked for below NEAR_FLOOR too
  where its residuals are strongly structured, :data:`STRUCTURE_P`): nothing is claimed;
* ``explained``: an accepted effect (or two, the waterfall) brings the held-out error
  back within ``tolerance`` × floor;
* ``unexplained``: structure above the floor remains that no candidate removes.

Where a step's error on its fitted window is known (``Step.train``), that must be at the
floor too: a held-out window that does not move (a record's relaxation tail after a
single inflation) is met by any model, and a model that misses the window it was fitted
to explains nothing there.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

VERDICTS = ("adequate", "explained", "unexplained")

#: held-out error within this factor of the noise floor counts as "at the floor"
TOLERANCE = 1.5
#: a base model between this factor of the floor and TOLERANCE is adequate only when no
#: candidate takes the held-out error below it, and by NEAR_GAIN of the base's at least:
#: clean recordings' base fits end at 0.91–1.10× (coverage_trace.py, 240 recordings of
#: three seeds); the amplifier with a hidden 6 mL dead volume, recorded on the logger's
#: own clock, ended at 1.46× and was called adequate
NEAR_FLOOR = 1.2
NEAR_GAIN = 0.1
#: a base model above the floor but within NEAR_FLOOR whose fitted residuals are this
#: strongly autocorrelated (Ljung–Box p-value below this) is screened too, and yields to
#: an effect NEAR_GAIN below it: the two tanks driven by a sine, heat exchange in tank 1,
#: base at 1.199× with p = 1e-230 was adequate with R₁ 5 % off; their clean records gave
#: p = 0.03–0.48 (white noise: p about uniform, the smallest of a record's signals
#: below 1e-6 about once per million signals)
STRUCTURE_P = 1e-6


@dataclass
class Step:
    """One bar of the error waterfall: the model after the effects in ``effects``."""

    label: str
    held_out: float  # held-out error (the diagnosis' unit)
    se: float = float("nan")  # its standard error, when known
    effects: tuple = ()
    extra: dict = field(default_factory=dict)
    train: float = float("nan")  # error on the fitted window, when known

    @property
    def worst(self) -> float:
        """The larger of the held-out and the fitted window's error (held-out alone
        when the fitted window's is not known)."""
        return self.held_out if math.isnan(self.train) else max(self.held_out, self.train)

    def to_json(self) -> dict:
        return {"label": self.label, "held_out_rms": _num(self.held_out),
                "held_out_se": _num(self.se), "train_rms": _num(self.train),
                "effects": list(self.effects), **self.extra}


def at_floor(error: float, floor: float, tolerance: float = TOLERANCE) -> bool:
    """True when ``error`` is within ``tolerance`` × ``floor``."""
    return bool(math.isfinite(error) and math.isfinite(floor) and error <= tolerance * floor)


def verdict(base_error: float, final_error: float, floor: float, accepted,
            structure_left: bool = False, tolerance: float = TOLERANCE) -> str:
    """The verdict word of a diagnosis.

    ``base_error``/``final_error``: held-out error of the base model and of the model
    with the ``accepted`` effects; ``structure_left``: a flexible residual model (or a
    locator) still finds structure the accepted effects leave.  An accepted effect
    counts only when it brings the error to the floor and leaves no structure."""
    if structure_left:
        return "unexplained"
    if accepted:
        return "explained" if at_floor(final_error, floor, tolerance) else "unexplained"
    return "adequate" if at_floor(base_error, floor, tolerance) else "unexplained"


def needs_candidates(base_error: float, floor: float, tolerance: float = TOLERANCE,
                     structured: bool = False) -> bool:
    """Whether a base model's held-out error is above :data:`NEAR_FLOOR` × ``floor``
    (or ``tolerance`` ×, if smaller), or with ``structured`` residuals
    (:data:`STRUCTURE_P`) above the floor: below it the base is adequate whatever a
    candidate does, above it the candidates are screened and :func:`decide` may accept
    one."""
    return not at_floor(base_error, floor, 1.0 if structured else min(NEAR_FLOOR, tolerance))


def strongly_structured(ljung_box_p: float) -> bool:
    """Whether residuals with this Ljung–Box p-value are structured enough to look for
    a missing effect below :data:`NEAR_FLOOR` × the floor (:data:`STRUCTURE_P`)."""
    return bool(math.isfinite(ljung_box_p) and ljung_box_p < STRUCTURE_P)


def step_tolerance(effects, tolerance: float = TOLERANCE, in_sample: bool = False) -> float:
    """The factor of the floor within which a model with ``effects`` counts as at the
    floor: ``tolerance``, or :data:`NEAR_FLOOR` for two effects or more fitted to the very
    samples they are judged on (``in_sample``: nothing held out; see :func:`decide`)."""
    return min(NEAR_FLOOR, tolerance) if in_sample and len(effects) > 1 else tolerance


def decide(steps: list[Step], floor: float, tolerance: float = TOLERANCE,
           in_sample: bool = False, structured: bool = False) -> tuple[str, list]:
    """(verdict, accepted effect names) from the waterfall ``steps`` (base first, then
    the model with 1, 2 … effects, each step's ``effects`` the whole set so far): the
    first step at the floor is accepted; for a base within ``tolerance`` but above
    :data:`NEAR_FLOOR` × floor, the first step below that and :data:`NEAR_GAIN` under
    the base (a base below that too, when its residuals are ``structured``:
    :func:`needs_candidates`).  ``in_sample``: nothing was held out (the errors are the
    fitted window's), and a step of two effects or more counts as at the floor only within
    :data:`NEAR_FLOOR` × floor: fitted to the very samples it is judged on, a pair
    mimics what the library lacks (the two tanks with a 30 mL dead end behind a line,
    each recorded once through the supply's step: heat exchange with a tube, 1.43× and
    1.38×, both lines' intervals missing the truth by 20 %)."""
    if not steps:
        raise ValueError("no waterfall steps")
    accepted = []
    base = steps[0].worst
    near = min(NEAR_FLOOR, tolerance)

    def bar(step):
        return step_tolerance(step.effects, tolerance, in_sample)

    if not at_floor(base, floor, tolerance):
        accepted = next((list(s.effects) for s in steps[1:]
                         if at_floor(s.worst, floor, bar(s))), [])
    elif needs_candidates(base, floor, tolerance, structured):
        accepted = next((list(s.effects) for s in steps[1:]
                         if at_floor(s.worst, floor, near)
                         and s.worst <= (1.0 - NEAR_GAIN) * base), [])
    final = next((s for s in steps if list(s.effects) == accepted), steps[0])
    return verdict(base, final.worst, floor, accepted, tolerance=bar(final)), accepted


def untested_note(steps: list[Step], floor: float, tolerance: float = TOLERANCE) -> str:
    """A sentence for the report when a step is at the floor on the held-out window but
    not on its fitted one ('' when none is)."""
    odd = [s for s in steps if at_floor(s.held_out, floor, tolerance)
           and not at_floor(s.worst, floor, tolerance)]
    if not odd:
        return ""
    return ("held out at the floor but not on the fitted window: " + "; ".join(
        f"{s.label} {s.held_out / floor:.2f}× held out, {s.train / floor:.2f}× fitted"
        for s in odd) + " (the held-out part tests little: such a step counts as not "
        "at the floor)")


#: rms residuals closer than this fraction fit alike whatever their standard error: a
#: difference far below the verdict's tolerance decides nothing
ALIKE_FRACTION = 0.01


def indistinguishable(a, b, sigmas: float = 2.0) -> bool:
    """Whether two models' residuals ``a`` and ``b`` (the same samples, NaN where one is
    not compared) fit alike: their rms within :data:`ALIKE_FRACTION` of each other, or
    the mean of a² − b² within ``sigmas`` standard errors of zero, the standard error by
    Newey–West (statsmodels' HAC) over √n lags, because a recording's residuals are
    autocorrelated over many samples."""
    import statsmodels.api as sm

    a, b = np.asarray(a, float), np.asarray(b, float)
    ok = np.isfinite(a) & np.isfinite(b)
    if ok.sum() < 10:
        return False
    ms_a, ms_b = float(np.mean(a[ok] ** 2)), float(np.mean(b[ok] ** 2))
    if abs(math.sqrt(ms_a) - math.sqrt(ms_b)) <= ALIKE_FRACTION * math.sqrt(min(ms_a, ms_b)):
        return True
    d = a[ok] ** 2 - b[ok] ** 2
    lags = int(math.sqrt(d.size))
    fit = sm.OLS(d, np.ones(d.size)).fit(cov_type="HAC", cov_kwds={"maxlags": lags})
    return bool(abs(fit.params[0]) <= sigmas * fit.bse[0])


def _num(v):
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None
