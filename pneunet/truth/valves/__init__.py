"""Truth-finding on valve bench data: identification of the six-parameter model
(:mod:`.identify`) and the diagnosis of what it misses from the valve-law effects
(:mod:`.diagnose`, effects in :mod:`pneunet.physics.valve_effects`).
May import: common, physics, engine, netlist, truth.core.
"""
