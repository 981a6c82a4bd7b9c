"""Pause Python's cyclic garbage collector while a large structure is built.

Building a 30,000-cell netlist allocates millions of objects; every 700 of them the
collector walks the young ones and, now and then, the whole heap, so the build time
grows faster than the circuit (measured: 25 % of the time at 10,000 cells,
``benchmarks/bench_frontend.py``).  Nothing built here is garbage until the build
ends, so pausing costs no memory.
"""
from __future__ import annotations

import gc
from contextlib import contextmanager


@contextmanager
def collector_paused():
    """Disable the cyclic collector inside the block (reference counting still frees
    memory), and restore its previous state after it."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()
