"""Workspace throughput: the CASPR neck's static workspace, case 3 with 15 deg cones on all 8 joints
(alpha 1/8, beta 0: the paper's settings), random poses in the joint ranges its roll, pitch and yaw
trajectories span.

What it measures, in one run:

1. ``mcdm-pin workspace`` (``compute_workspace``, scheduler ``local``) on 1 and on 2 worker processes:
   poses per second from the first task submitted to the last chunk written (the cluster's start-up
   is reported apart), and the parallel efficiency ``rate(2) / (2 rate(1))``;
2. the same sample solved by Clarabel called directly (conic form + ``clarabel.DefaultSolver``, default
   settings, one process), timed per pose, and its agreement with the store: the status (optimal or
   infeasible) and the objective to 1e-6 relative on every pose;
3. the Dask scheduler's overhead per task: the round trip of one no-op task at a time (latency) and
   the time per task of many no-op tasks in flight on 2 workers (throughput), and the client's time
   to write one chunk into the store, from which docs/workspace.md models the throughput on N
   machines.

Usage::

    python benchmarks/workspace.py [--poses 100000] [--chunk 256] [--seed 0] [--no-margins]
        [--clarabel-poses N] [--caspr DIR] [--json FILE] [--markdown FILE]

The neck is ``robots/8S_neck.yaml`` when the repository has it, else it is imported from CASPR's files
(``--caspr``: the committed conversion under robots/caspr by default, or CASPR's XML files).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import DEFAULT_CASPR, REPO, import_neck, machine, neck_case_options  # noqa: E402

OBJ_RTOL = 1e-6  # agreement of the objective with Clarabel's, relative (absolute below 1)


def load_neck(tmp: Path, caspr: Path):
    """The neck robot and the coordinate ranges its roll, pitch and yaw trajectories span."""
    from mcdm_pin import Robot, load_trajectory

    robot = Robot.load(import_neck(caspr, tmp / "neck", ["roll", "pitch", "yaw"]).sidecar)
    q = np.vstack([load_trajectory(robot, name).q for name in ("roll", "pitch", "yaw")])
    lo, hi = q.min(axis=0), q.max(axis=0)
    ranges = {c: (float(a), float(b)) for c, a, b in zip(robot.coordinate_names, lo, hi) if b > a}
    at = {c: float(a) for c, a, b in zip(robot.coordinate_names, lo, hi) if not b > a}
    return robot, ranges, at


def run_workers(robot, poses, setup, chunk, workers, tmp):
    from mcdm_pin.workspace import compute_workspace

    report = compute_workspace(robot, poses, tmp / f"neck_{workers}.zarr", setup, chunk=chunk,
                               scheduler="local", workers=workers, progress=sys.stderr.isatty())
    return report


def clarabel_direct(robot, setup, q, store):
    """Clarabel on every pose of ``q``: time per pose and agreement with the store's answers."""
    import clarabel

    from mcdm_pin.solvers.clarabel_ import conic_form
    from mcdm_pin.workspace import PoseSolver

    assembler = PoseSolver(robot, setup)
    status, objective = store["status"].values[:len(q)], store["objective"].values[:len(q)]
    times, disagree = [], []
    for k, pose in enumerate(q):
        qp = assembler.assemble(pose)
        t0 = time.perf_counter()
        P, c, A, b, cones, _ = conic_form(qp)
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        sol = clarabel.DefaultSolver(P, c, A, b, cones, settings).solve()
        times.append(time.perf_counter() - t0)
        word = str(sol.status)
        ok = word in ("Solved", "AlmostSolved")
        theirs = "optimal" if ok else ("infeasible" if "Infeasible" in word else word)
        value = qp.objective(np.array(sol.x)) if ok else float("nan")
        same = theirs == status[k] and (not ok or abs(value - objective[k])
                                        <= OBJ_RTOL * max(1.0, abs(value)))
        if not same:
            disagree.append(dict(pose=k, ours=str(status[k]), clarabel=theirs,
                                 objective_ours=float(objective[k]), objective_clarabel=float(value)))
    t = np.array(times)
    return dict(poses=len(q), poses_per_s=len(q) / t.sum(), p50_ms=1e3 * np.median(t),
                p99_ms=1e3 * np.percentile(t, 99), disagreements=len(disagree), examples=disagree[:10])


def scheduler_overhead(tasks: int = 400, latency_tasks: int = 50) -> dict:
    """Per-task cost of the Dask scheduler on 2 local workers: no-op tasks, one at a time and many in
    flight."""
    import logging

    from dask.distributed import Client, LocalCluster, wait

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        client.submit(_noop, 0, pure=False).result()
        t0 = time.perf_counter()
        for k in range(latency_tasks):
            client.submit(_noop, k, pure=False).result()
        latency = (time.perf_counter() - t0) / latency_tasks
        t0 = time.perf_counter()
        wait([client.submit(_noop, k, pure=False) for k in range(tasks)])
        per_task = (time.perf_counter() - t0) / tasks
    return dict(round_trip_ms=1e3 * latency, in_flight_per_task_ms=1e3 * per_task, tasks=tasks)


def write_time(path, store, chunk: int, repeat: int = 5) -> float:
    """Median time for the client to write one chunk's results into the store, ms (chunk 0 written
    again with its own values)."""
    from mcdm_pin.workspace.store import RESULT_VARIABLES, Writer

    writer = Writer(path, chunk)
    results = {v: store[v].values[:chunk] for v in RESULT_VARIABLES}
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        writer.write(0, results)
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def _noop(x):
    return x


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--poses", type=int, default=100_000)
    p.add_argument("--chunk", type=int, default=256)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--no-margins", action="store_true", help="solve only (margins stored as NaN)")
    p.add_argument("--clarabel-poses", type=int, help="Clarabel on the first N poses (default: all)")
    p.add_argument("--caspr", type=Path, default=DEFAULT_CASPR)
    p.add_argument("--json", type=Path)
    p.add_argument("--markdown", type=Path)
    args = p.parse_args(argv)

    from mcdm_pin.workspace import RandomPoses, Setup, open_workspace

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        robot, ranges, at = load_neck(tmp, args.caspr)
        opts = neck_case_options(robot.joint_names)[3]
        setup = Setup(case=3, cones=opts["cones"], alpha=opts["alpha"], beta=opts["beta"],
                      margins=not args.no_margins)
        poses = RandomPoses(robot, args.poses, seed=args.seed, ranges=ranges, at=at)
        runs = {}
        for workers in (1, 2):
            rep = run_workers(robot, poses, setup, args.chunk, workers, tmp)
            runs[workers] = dict(poses_per_s=rep.poses_per_s, compute_s=rep.compute_s,
                                 startup_s=rep.startup_s)
            print(f"{workers} worker(s): {rep.poses_per_s:.1f} poses/s ({rep.compute_s:.1f} s, start-up "
                  f"{rep.startup_s:.1f} s)", flush=True)
        store = open_workspace(tmp / "neck_2.zarr")
        reference = open_workspace(tmp / "neck_1.zarr")
        same = all(np.array_equal(store[v].values, reference[v].values) for v in ("status",))
        n_c = min(args.clarabel_poses or args.poses, args.poses)
        clar = clarabel_direct(robot, setup, poses.chunk(0, n_c), store)
        words, counts = np.unique(store["status"].values, return_counts=True)
        overhead = scheduler_overhead()
        overhead["write_chunk_ms"] = write_time(tmp / "neck_2.zarr", store, args.chunk)
    eff = runs[2]["poses_per_s"] / (2 * runs[1]["poses_per_s"])
    result = dict(machine=machine(), poses=args.poses, chunk=args.chunk, seed=args.seed,
                  margins=not args.no_margins, runs=runs, efficiency=eff, statuses_equal_1_vs_2=same,
                  status={str(w): int(c) for w, c in zip(words, counts)}, clarabel=clar,
                  scheduler=overhead)
    table = markdown(result)
    print(table)
    if args.json:
        args.json.write_text(json.dumps(result, indent=2, default=float))
    if args.markdown:
        args.markdown.write_text(table + "\n")
    return 0


def markdown(r: dict) -> str:
    m = r["machine"]
    c = r["clarabel"]
    lines = [f"neck, case 3, 15 deg cones, {r['poses']} random poses (seed {r['seed']}), chunks of "
             f"{r['chunk']}, margins {'on' if r['margins'] else 'off'}; {m['cpu']}, {m['nproc']} cores, "
             f"load {m['load_avg_1min']}",
             "", "| | poses/s | wall s | start-up s |", "|---|---|---|---|"]
    for w, run in r["runs"].items():
        lines.append(f"| ours, {w} worker{'s' if int(w) > 1 else ''} | {run['poses_per_s']:.1f} | "
                     f"{run['compute_s']:.1f} | {run['startup_s']:.1f} |")
    lines.append(f"| Clarabel direct, 1 process ({c['poses']} poses; p50 {c['p50_ms']:.2f} ms, "
                 f"p99 {c['p99_ms']:.2f} ms) | {c['poses_per_s']:.1f} | | |")
    lines += ["", f"parallel efficiency (2 workers): {100 * r['efficiency']:.1f} %; statuses "
              f"{r['status']}; agreement with Clarabel (status, objective to {OBJ_RTOL:g}): "
              f"{c['poses'] - c['disagreements']} of {c['poses']} poses",
              f"Dask scheduler, 2 local workers: {r['scheduler']['round_trip_ms']:.2f} ms per no-op task "
              f"one at a time, {r['scheduler']['in_flight_per_task_ms']:.2f} ms per task with "
              f"{r['scheduler']['tasks']} in flight; the client writes a chunk in "
              f"{r['scheduler']['write_chunk_ms']:.1f} ms"]
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
