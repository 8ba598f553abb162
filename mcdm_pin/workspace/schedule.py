"""Chunks of poses -> Dask tasks -> the Zarr store, as they finish.

``scheduler``:

- ``"local"`` (default): a Dask ``LocalCluster`` on this machine, one single-threaded worker process
  per core (``workers`` to choose), on the loopback interface; nothing to set up.
- ``"tcp://HOST:PORT"``: a running Dask scheduler (``dask scheduler``) with workers attached
  (``dask worker tcp://HOST:PORT --nthreads 1``); ``workers``: wait until that many are connected.
- ``"inline"``: in this process, without Dask (debugging, small runs, tests).

The client holds a few chunks per worker thread in flight (not the whole run), writes each chunk's
results as it arrives and submits the next; the robot goes to every worker once (scattered, as
pickled data). A progress bar (``tqdm``) shows the poses done, the rate and the time left.

The scheduler is reached before the store is created, so an unreachable one leaves nothing behind.
Ctrl-C: local workers are started with SIGINT ignored (a terminal sends it to the whole process
group), this process closes the cluster and raises :class:`WorkspaceInterrupted`, whose message says
how many chunks the store keeps (``--resume`` completes it).
"""

from __future__ import annotations

import json
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..extras import optional
from ..runtime import check_scheduler, close, connect
from .errors import WorkspaceError, WorkspaceInterrupted
from .evaluate import PoseSolver, RobotBlob, Setup, robot_digest, solve_chunk
from .store import FORMAT, Writer, create_store, open_for_resume, open_workspace

DEFAULT_CHUNK = 256  # poses per task (docs/workspace.md: a few hundred ms of work per task)
IN_FLIGHT_PER_THREAD = 2  # chunks queued per worker thread, so that none waits for the client
CONNECT_TIMEOUT_S = 20  # to reach a tcp:// scheduler


@dataclass
class RunReport:
    """What a call of :func:`compute_workspace` did."""

    path: Path
    poses: int  # in the store
    chunks: int  # in the store
    computed_chunks: int  # by this call (the others were done already)
    computed_poses: int
    workers: int  # worker threads that took part
    scheduler: str
    startup_s: float  # starting or reaching the cluster
    compute_s: float  # from the first task submitted to the last chunk written
    recomputed: dict = field(default_factory=dict)  # chunk -> why its done flag was not trusted

    @property
    def poses_per_s(self) -> float:
        return self.computed_poses / self.compute_s if self.compute_s > 0 else float("nan")

    def open(self):
        """The store as an ``xarray.Dataset``."""
        return open_workspace(self.path)


def settings(robot, poses, setup: Setup, chunk: int) -> dict:
    """The store's ``workspace`` attribute: everything that defines its contents (not how it is
    computed: scheduler and workers may change between a run and its resumption)."""
    from .. import __version__

    ident = setup.identify(robot)
    out = dict(format=FORMAT, mcdm_pin=__version__,
               robot=dict(name=robot.name, sidecar=str(getattr(robot.sidecar, "path", "")),
                          sha256=robot_digest(robot)),
               problem=f"case {setup.case}: {ident.problem.describe()}", setup=setup.describe(),
               cones_deg={j: float(a) for j, a in zip(robot.joint_names, ident.cone_deg) if a == a},
               f_min=[float(x) for x in robot.f_min], f_max=[float(x) for x in robot.f_max],
               poses=poses.describe(), chunk=int(chunk),
               start="cold: every pose solved alone, without warm start",
               margins=("needed_f_max: LP min t s.t. A f = b, f_min <= f <= t; needed_cone_deg: "
                        "smallest common cone angle, a generalized fractional program (mcdm_pin/solvers/margins.py)")
               if setup.margins else "not computed")
    return json.loads(json.dumps(out))  # as the store gives it back (lists, not tuples)


def compute_workspace(robot, poses, out, setup: Setup | None = None, chunk: int | None = None,
                      scheduler: str = "local", workers: int | None = None, resume: bool = False,
                      progress: bool | None = None) -> RunReport:
    """Compute a workspace into the Zarr store ``out``.

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot`.
        poses: a pose set (:class:`~mcdm_pin.workspace.Grid`, :class:`RandomPoses`,
            :class:`PosesFile`).
        out: the store's path (``.zarr``); must not exist unless ``resume``.
        setup: the problem (:class:`Setup`; default case 1, static).
        chunk: poses per task and per Zarr chunk (default 256).
        scheduler: ``local`` (default), ``tcp://HOST:PORT`` or ``inline`` (module docstring).
        workers: local worker processes (default: the machine's cores); for a cluster, wait until
            that many workers are connected.
        resume: complete an existing store: compute only its missing chunks (the settings must
            match the store's).
        progress: show a progress bar (default: when stderr is a terminal).
    """
    setup = setup or Setup()
    chunk = DEFAULT_CHUNK if chunk is None else chunk
    if int(chunk) != chunk or chunk < 1:
        raise WorkspaceError(f"chunk: expected a positive number of poses, got {chunk!r}")
    chunk = min(int(chunk), len(poses))
    check_scheduler(scheduler, workers, WorkspaceError)
    out = Path(out)
    wanted = settings(robot, poses, setup, chunk)
    nchunks = -(-len(poses) // chunk)
    resuming = resume and out.exists()
    damaged: dict[int, str] = {}
    if resuming:
        todo, damaged = open_for_resume(out, wanted)
    elif out.exists():
        raise WorkspaceError(f"{out}: already exists; give --resume to complete it, or another --out")
    else:
        todo = list(range(nchunks))
    if progress is None:
        progress = sys.stderr.isatty()
    sizes = {k: min(chunk, len(poses) - k * chunk) for k in todo}
    t0 = time.perf_counter()
    client = cluster = bar = None
    try:  # the scheduler is reached before the store is made: an unreachable one leaves nothing
        if scheduler != "inline":
            client, cluster = connect(scheduler, workers, CONNECT_TIMEOUT_S, WorkspaceError)
        if not resuming:
            create_store(out, robot, poses, chunk, wanted)
        writer = Writer(out, chunk)
        if progress:
            bar = _bar(len(poses), len(poses) - sum(sizes.values()))
        if client is None:
            solver = PoseSolver(robot, setup)
            startup, t0 = time.perf_counter() - t0, time.perf_counter()
            for k in todo:
                writer.write(k, solver.solve(poses.chunk(k * chunk, k * chunk + sizes[k])))
                if bar is not None:
                    bar.update(sizes[k])
            threads = 1
        else:
            startup, t0, threads = _run_dask(client, robot, poses, setup, chunk, todo, sizes, writer,
                                             bar, scheduler, t0)
        elapsed = time.perf_counter() - t0
    except KeyboardInterrupt:
        raise _interrupted(out, nchunks) from None
    finally:
        if bar is not None:
            bar.close()
        close(client, cluster)
    return RunReport(out, len(poses), nchunks, len(todo), sum(sizes.values()), threads, scheduler,
                     startup, elapsed, damaged)


def _interrupted(out: Path, nchunks: int) -> WorkspaceInterrupted:
    try:
        zarr = optional("zarr", "workspaces")

        done = int(np.sum(zarr.open_group(str(out), mode="r", zarr_format=2)["chunk_done"][:] == 1))
    except Exception:  # noqa: BLE001 - no store yet (interrupted while starting)
        done = -1
    return WorkspaceInterrupted(out, done, nchunks)


def _bar(total: int, initial: int):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit="pose", file=sys.stderr, smoothing=0.1,
                desc="workspace", dynamic_ncols=True)


def _run_dask(client, robot, poses, setup, chunk, todo, sizes, writer, bar, scheduler, t0):
    threads = sum(client.nthreads().values())
    if threads < 1:
        raise WorkspaceError(f"scheduler {scheduler}: no worker is connected (start some with "
                             f"dask worker {scheduler} --nthreads 1)")
    robot_future = client.scatter(RobotBlob(robot), broadcast=True)
    startup = time.perf_counter() - t0
    t0 = time.perf_counter()
    _pump(client, robot_future, poses, setup, chunk, todo, sizes, writer, bar,
          IN_FLIGHT_PER_THREAD * threads)
    return startup, t0, threads


def _pump(client, robot_future, poses, setup, chunk, todo, sizes, writer, bar, in_flight):
    """Keep ``in_flight`` chunks submitted; write each as it finishes, then submit the next."""
    as_completed = optional("dask.distributed", "workspaces").as_completed

    queue = deque(todo)
    running = {}
    done = as_completed()

    def submit():
        k = queue.popleft()
        q = poses.chunk(k * chunk, k * chunk + sizes[k])
        fut = client.submit(solve_chunk, robot_future, setup, q, pure=False)
        running[fut] = k
        done.add(fut)

    for _ in range(min(in_flight, len(queue))):
        submit()
    for fut in done:
        k = running.pop(fut)
        writer.write(k, fut.result())
        fut.release()
        if bar is not None:
            bar.update(sizes[k])
        if queue:
            submit()
