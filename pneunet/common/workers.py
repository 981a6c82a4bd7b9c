"""Local worker processes that never outlive their parent.

:func:`process_pool` makes a pool of them; a :class:`Servant` is one object moved into a
worker of its own whose methods the parent calls.  A worker dies with the process that made the pool, however
that process ends (SIGKILL included): on Linux the kernel kills it
(``prctl(PR_SET_PDEATHSIG, SIGKILL)``), and everywhere a watchdog thread ends it within
:data:`WATCH_S` seconds of its parent's death.  Workers ignore SIGINT: on Ctrl-C the
parent stops them with :func:`stop` and keeps what has finished.
"""
from __future__ import annotations

import os
import signal
import sys
import threading
import time

#: seconds between the watchdog's checks that the parent is alive
WATCH_S = 0.5
_PR_SET_PDEATHSIG = 1


def process_pool(workers: int):
    """A fork-based ``ProcessPoolExecutor`` of ``workers`` guarded processes, or None
    when this process cannot fork workers (:func:`can_fork`) or ``workers`` < 2."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    if workers < 2 or not can_fork():
        return None
    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("fork"),
                               initializer=_guard, initargs=(os.getpid(),))


class Servant:
    """An object built by ``make(*args)`` in a forked worker process of its own (the
    parent never holds it), its methods called over a pipe.

    ``call(name, *args)`` runs ``obj.name(*args)`` there and returns the result;
    ``send`` and ``receive`` split that, so that several servants work at once.  What
    ``make`` or the method raises is raised in the parent.  Memory the parent shares with
    the fork (an anonymous shared ``mmap``) is the way to return bulk results.
    """

    def __init__(self, make, *args):
        import multiprocessing

        context = multiprocessing.get_context("fork")
        self._conn, theirs = context.Pipe()
        self._process = context.Process(target=_serve, args=(make, args, theirs, os.getpid()),
                                        daemon=True)
        self._process.start()
        theirs.close()
        self._built = False

    def send(self, name: str, *args) -> None:
        if not self._built:  # the worker first says whether make() worked
            self._built = True
            self.receive()
        self._conn.send((name, args))

    def receive(self):
        status, value = self._conn.recv()
        if status == "error":
            raise value
        return value

    def call(self, name: str, *args):
        self.send(name, *args)
        return self.receive()

    def close(self) -> None:
        """End the worker (at once if it is busy)."""
        try:
            self._conn.send(None)
        except OSError:
            pass
        self._process.join(timeout=1)
        if self._process.is_alive():
            self._process.kill()
            self._process.join()
        self._conn.close()


def can_fork() -> bool:
    """Whether this process may fork workers: fork exists here, and this is not a
    daemonic process (a multiprocessing pool's or a dask worker), which may have none."""
    import multiprocessing

    return ("fork" in multiprocessing.get_all_start_methods()
            and not multiprocessing.current_process().daemon)


def _serve(make, args, conn, parent: int) -> None:
    _guard(parent)
    try:
        obj = make(*args)
    except Exception as exc:
        conn.send(("error", exc))
        return
    conn.send(("ok", None))
    while True:
        try:
            request = conn.recv()
        except EOFError:
            return
        if request is None:
            return
        name, args = request
        try:
            reply = ("ok", getattr(obj, name)(*args))
        except Exception as exc:  # raised again in the parent
            reply = ("error", exc)
        conn.send(reply)


def stop(pool) -> None:
    """End ``pool`` now: pending work cancelled, running workers killed (after Ctrl-C;
    a second Ctrl-C meanwhile is ignored, so the stop completes)."""
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:
        processes = list((getattr(pool, "_processes", None) or {}).values())
        for process in processes:  # first: nothing below then waits on a running worker
            if process.is_alive():
                process.kill()
        # the executor's manager thread sees the dead workers, fails every pending future
        # and ends; only then its shutdown (a future cancelled before that makes the
        # manager's set_exception raise InvalidStateError on Python 3.11: a traceback)
        manager = getattr(pool, "_executor_manager_thread", None)
        if manager is not None:  # else the interpreter waits for it at exit
            manager.join(timeout=5)
        # the executor's own shutdown takes its locks: never let it hold up the stop
        closer = threading.Thread(target=pool.shutdown, daemon=True, name="pool-stop",
                                  kwargs={"wait": False, "cancel_futures": True})
        closer.start()
        closer.join(timeout=5)
        for process in processes:
            process.join(timeout=5)
    finally:
        if main:
            signal.signal(signal.SIGINT, previous)


def _guard(parent: int) -> None:
    """Worker initializer: die with ``parent``; leave SIGINT to the parent."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:  # the parent died before the guard was set
        os._exit(1)
    threading.Thread(target=_watch, args=(parent,), daemon=True, name="parent-watch").start()


def _watch(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(WATCH_S)
    os._exit(1)
