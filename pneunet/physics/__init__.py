"""Physics: gases and liquids (:mod:`.gas`, :mod:`.liquids`), the flow laws of the paper
(:mod:`.laws`), valve parameters (:mod:`.valve_params`), source waveforms
(:mod:`.waveforms`), data tables (:mod:`.tables`), units for each fluid (:mod:`.units`),
the element families (:mod:`.elements`), valve-law effects (:mod:`.valve_effects`,
usable in netlists and fitted by the valve diagnosis) and the relaxation oscillator's
stationary branches (:mod:`.oscillator_branches`).  May import: common.
"""
