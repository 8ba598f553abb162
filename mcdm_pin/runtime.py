"""The Dask runtime that workspaces (:mod:`mcdm_pin.workspace`) and batch trajectories
(:mod:`mcdm_pin.batch`) share. ``scheduler``:

- ``"local"``: a Dask ``LocalCluster`` on this machine, ``workers`` single-threaded worker processes
  (default: one per core), on the loopback interface; nothing to set up.
- ``"tcp://HOST:PORT"``: a running Dask scheduler (``dask scheduler``) with workers attached
  (``dask worker tcp://HOST:PORT --nthreads 1``); ``workers``: wait until that many are connected.
- ``"inline"``: in this process, without Dask.

Local workers start with SIGINT ignored (a terminal sends Ctrl-C to the whole process group; only
the client acts on it and closes the cluster). Dask is the ``workspace`` extra.
"""

from __future__ import annotations

import logging
import os
import signal
import threading
from contextlib import contextmanager

from .extras import optional

SCHEDULERS = "local, inline or tcp://HOST:PORT"
WAIT_FOR_WORKERS_S = 120


def check_scheduler(scheduler: str, workers: int | None, error=ValueError) -> None:
    """Raise ``error`` unless ``scheduler`` is one of :data:`SCHEDULERS` and ``workers`` fits it."""
    if scheduler not in ("local", "inline") and not str(scheduler).startswith("tcp://"):
        raise error(f"scheduler: expected {SCHEDULERS}, got {scheduler!r}")
    if workers is not None and (int(workers) != workers or workers < 1):
        raise error(f"workers: expected a positive number, got {workers!r}")
    if scheduler == "inline" and workers not in (None, 1):
        raise error("scheduler inline runs in this process: workers must be 1")


@contextmanager
def workers_ignore_ctrl_c():
    """Start local worker processes with SIGINT ignored (a disposition a child inherits, and Python
    keeps at start-up): Ctrl-C in a terminal reaches the whole process group, and only this process,
    which then closes the cluster, should act on it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def connect(scheduler: str, workers: int | None, timeout_s: float, error=ValueError):
    """``(client, cluster)`` of ``scheduler`` (``local`` or ``tcp://``; ``cluster`` is ``None`` for a
    running scheduler); ``error`` (an exception type) names an unreachable one."""
    distributed = optional("dask.distributed", "the Dask scheduler (workspaces, batch trajectories)",
                           "workspace")
    if scheduler == "local":
        # the local cluster's own log stays quiet below CRITICAL: what it says at ERROR is its shutdown
        # (a worker whose heartbeat finds the scheduler closed first, after Ctrl-C), while a task's
        # error reaches this process as the task's exception and a lost worker as KilledWorker
        with workers_ignore_ctrl_c():
            cluster = distributed.LocalCluster(
                n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                host="127.0.0.1", dashboard_address="127.0.0.1:0", silence_logs=logging.CRITICAL)
        return distributed.Client(cluster), cluster
    try:
        client = distributed.Client(scheduler, timeout=f"{timeout_s}s")
    except OSError as exc:
        raise error(f"scheduler {scheduler}: cannot connect ({exc}); start one with "
                    f"dask scheduler, and workers with dask worker {scheduler}") from None
    if workers:
        try:
            client.wait_for_workers(workers, timeout=WAIT_FOR_WORKERS_S)
        except TimeoutError:
            have = len(client.scheduler_info()["workers"])
            client.close()
            raise error(f"scheduler {scheduler}: {have} workers connected after {WAIT_FOR_WORKERS_S} s, "
                        f"{workers} requested") from None
    return client, None


def close(client, cluster) -> None:
    """Close the Dask client and local cluster, quietly (also after Ctrl-C)."""
    for thing in (client, cluster):
        if thing is not None:
            try:
                thing.close()
            except (Exception, KeyboardInterrupt):  # noqa: BLE001 - best effort on the way out
                pass


__all__ = ["SCHEDULERS", "check_scheduler", "connect", "close", "workers_ignore_ctrl_c"]
