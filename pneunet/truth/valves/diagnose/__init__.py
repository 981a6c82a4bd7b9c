"""Model vs measurement diagnosis (issue 5): where the valve model fails, which
physical effect is missing, and how much error adding it removes.

``diagnose(data) -> Diagnosis`` (``.report()``, ``.to_json()``, ``.plots(dir)``,
``.model_card(name)``); candidate effects come from :mod:`pneunet.physics.valve_effects`.
"""
from __future__ import annotations

from .core import Candidate, Diagnosis, Stage, diagnose
from .fitting import fit_model

__all__ = ["Candidate", "Diagnosis", "Stage", "diagnose", "fit_model"]
