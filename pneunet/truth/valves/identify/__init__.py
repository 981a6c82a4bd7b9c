"""Valve characterisation: measured data in, the six parameters out (paper secs. 4–5).

* :func:`load_measurements` — read and check bench data (CSV or DataFrame)
* :func:`simulate_bench` — the paper's protocol run on any flow model
* :func:`fit_valve` — two-stage identification (linear SVM, then least squares)
* :mod:`.analyses` — open-valve check, areas vs threshold, mirror valve, seat height
* :mod:`.plots` — the paper's Figs. 6–9
"""
from __future__ import annotations

from .bench import OutletRegulator, paper_protocol, simulate_bench
from .data import Measurements, load_measurements
from .fit import ValveFit, fit_valve

__all__ = ["Measurements", "OutletRegulator", "ValveFit", "fit_valve", "load_measurements",
           "paper_protocol", "simulate_bench"]
