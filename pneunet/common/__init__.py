"""Foundation shared by every stage: errors (:mod:`.errors`), report formatting
(:mod:`.reprs`), progress bars, worker pools (:mod:`.workers`), garbage-collector pauses,
matplotlib helpers (:mod:`.plotting`), robust CSV reading (:mod:`.csvdata`), the
solver's captured messages (:mod:`.solver_messages`) and the views later stages provide
(:mod:`.views`).  May import: nothing else of pneunet.
"""
