"""What users touch: the command line (:mod:`.cli`), the schematic (:mod:`.schematic`)
and the whole-run file (:mod:`.runfile`).  May import every stage.
"""
