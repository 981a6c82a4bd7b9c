"""``--dask ADDRESS|local``: the executor of commands that run on the sweep machinery."""
from __future__ import annotations

import contextlib


def add_executor_args(parser) -> None:
    """``--workers N`` and ``--dask ADDRESS|local`` (read by :func:`dask_or_local`)."""
    from .numbers import whole

    parser.add_argument("--workers", type=whole(1, MAX_WORKERS), default=None,
                        help="local worker processes (default: all cores; 1 = no pool)")
    parser.add_argument("--dask", metavar="ADDRESS", default=None,
                        help="run on a dask.distributed scheduler (ADDRESS, or 'local' for a "
                             "LocalCluster on this machine)")


#: local worker processes at most (each is a Python process of its own)
MAX_WORKERS = 256


@contextlib.contextmanager
def dask_or_local(address: str | None, workers: int | None):
    """A ``dask.distributed`` client (``'local'``: a LocalCluster of ``workers`` processes,
    default 2) closed on exit, or None (run_sweep's local process pool)."""
    if not address:
        yield None
        return
    from distributed import Client, LocalCluster

    cluster = None
    if address == "local":
        cluster = LocalCluster(n_workers=workers or 2, threads_per_worker=1,
                               dashboard_address=None)
        client = Client(cluster)
    else:
        client = Client(address)
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
