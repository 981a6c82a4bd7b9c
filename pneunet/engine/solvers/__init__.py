"""Numerical solvers: steady states (Newton), folds and jumps, transients (IDA backends)."""
from __future__ import annotations


def available_backends() -> dict:
    """{name: factory} of the IDA bindings importable on this machine."""
    import importlib.util

    out = {}
    if importlib.util.find_spec("sksundae") is not None:
        from .sundae import SundaeIntegrator

        out["sksundae"] = SundaeIntegrator
    if importlib.util.find_spec("scikits") is not None and \
            importlib.util.find_spec("scikits.odes") is not None:
        try:
            from .odes import OdesIntegrator
        except ModuleNotFoundError:  # binding installed, pneunet adapter not present
            pass
        else:
            out["odes"] = OdesIntegrator
    return out
