"""Numerical solvers: steady states (Newton) and transients (IDA backends)."""
