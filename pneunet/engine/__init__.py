"""Engine: a :class:`~.circuit.Circuit` of elements becomes a DAE (:mod:`.assembly`),
solved by SUNDIALS IDA or the multirate scheme (:mod:`.simulate`, :mod:`.single_rate`,
:mod:`.multirate`, :mod:`.solvers`) into a :class:`~.solution.Solution`; measurements
on its signals (:mod:`.measure`, :mod:`.oscillation`).  Knows no netlist language.
May import: common, physics.
"""
