"""A sweep on a ``dask.distributed`` cluster: points in batches, results streamed.

One task per point made a cluster pay per point what a local fork pool pays once: the
builder and analysis shipped and unpickled (a netlist parsed again), a task scheduled,
a result sent back.  Here the points go out in a few batches per worker thread, each
batch one task that builds and analyses its points in turn; a finished batch's records
are handed to ``finish`` (the store, the progress bar) as soon as it comes back.
Batches shrink towards the end (guided scheduling), so the workers finish together.
"""
from __future__ import annotations

import math

#: batches are the points left over this many times the worker threads (guided scheduling)
BATCHES_PER_THREAD = 3


def batch_sizes(n: int, threads: int) -> list[int]:
    """Sizes of the batches of ``n`` points for ``threads`` worker threads: each the
    points left divided by ``BATCHES_PER_THREAD * threads``, rounded up (36, 27, … 1)."""
    sizes, left = [], n
    while left > 0:
        size = math.ceil(left / (BATCHES_PER_THREAD * max(threads, 1)))
        sizes.append(size)
        left -= size
    return sizes


def evaluate_batch(evaluate, build, analysis, points: list, keep_traces: bool) -> list[dict]:
    """``evaluate(build, analysis, point, keep_traces)`` for each point, in this worker:
    ``build`` and ``analysis`` unpickled once for the batch (a netlist parsed once)."""
    return [evaluate(build, analysis, p, keep_traces) for p in points]


def run_on_dask(client, evaluate, build, analysis, points: list, keep_traces: bool,
                finish) -> int:
    """Evaluate ``points`` on ``client``'s cluster with ``evaluate`` (the sweep's
    ``evaluate_point``), calling ``finish(record)`` for every point of a batch as the batch
    finishes; returns the number of workers.  Pending batches are cancelled when this is
    interrupted."""
    import numpy as np
    from distributed import as_completed

    workers = client.scheduler_info().get("workers", {})
    threads = sum(w.get("nthreads", 1) for w in workers.values()) or 1
    # a fixed shuffle: each batch spans the grid, not one costly corner of it
    order = [points[i] for i in np.random.default_rng(0).permutation(len(points))]
    futures, start = [], 0
    for size in batch_sizes(len(order), threads):
        futures.append(client.submit(evaluate_batch, evaluate, build, analysis,
                                     order[start:start + size], keep_traces, pure=False))
        start += size
    try:
        for fut in as_completed(futures):
            for record in fut.result():
                finish(record)
            fut.release()
    except BaseException:
        client.cancel(futures)
        raise
    return len(workers) or 1
