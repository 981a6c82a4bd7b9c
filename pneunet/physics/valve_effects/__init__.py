"""Effect library: documented, composable extensions of the six-parameter valve model.

Library effects (ids): ``choked``, ``leak``, ``laminar``, ``internal-drop``,
``hysteresis``, ``pressure-offset``.  A :class:`ValveModel` combines a
:class:`~pneunet.physics.valve_params.ValveParams` with any of them; users add their own
with :func:`register_effect` (see :mod:`pneunet.physics.valve_effects.base`).
"""
from __future__ import annotations

from .base import (Effect, Inputs, Param, as_effect, available_effects, get_effect,
                   register_effect, unregister_effect)
from .model import ValveModel

LIBRARY_EFFECTS = ("choked", "leak", "laminar", "internal-drop", "hysteresis", "pressure-offset")

__all__ = ["Effect", "Inputs", "Param", "ValveModel", "as_effect", "available_effects",
           "get_effect", "register_effect", "unregister_effect", "LIBRARY_EFFECTS"]
