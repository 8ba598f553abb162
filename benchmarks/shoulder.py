"""The thoracoscapular shoulder (robots/opensim/tsm_rmr.yaml: 17 DoF, an acromioclavicular loop, 33
muscles over OpenSim's wraps, 17 coordinate actuators): per-frame time of mcdm-pin against Clarabel in the
same run, against the RMR solver's reported 0.16-0.21 s per frame (Belli et al. 2023, ``tOptim*.mat``).

    python benchmarks/shoulder.py [--motion robots/opensim/motions/abd01] [--case 1c 3] [--repeat 3]
        [--check 5] [--json FILE]

On the ABD01 motion (the committed 20 Hz excerpt by default; a folder with the full tables gives every
100 Hz frame), for ``1c`` (RMR's problem with the glenohumeral cone: activations and the actuators'
``w c^2``, mcdm_pin.osim.rmr) and case 3 (interactions with the same cone):

- **ours** (``InverseDynamics``, default solver chain) and **Clarabel** (``solver="clarabel"``), their
  runs taken in turns (:func:`myoarm.time_case`). *Warm*: ``solve_trajectory`` along the frames, after
  one untimed run. *Cold*: every frame alone in a shuffled order after ``reset()``. Cells: median and
  99th percentile per frame, ms.
- **check**: before timing, both back-ends on ``--check`` frames against Clarabel at 1e-11.

One BLAS thread (threadpoolctl). The machine is shared: the 1-minute load average is printed at the
start and the end, with the busiest processes.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import REPO, machine  # noqa: E402
from bench_id import stats_ms  # noqa: E402
from myoarm import BACKENDS, _cell, check, time_case, top_processes  # noqa: E402

DEFAULT_MOTION = REPO / "robots" / "opensim" / "motions" / "abd01"
RMR_PER_FRAME_S = (0.16, 0.21)  # RMR's own joint-reaction code (README of ../shared/reference/rmr)


def load(motion: Path):
    """The robot (RMR's pose of the TSM) and the motion's frames as a Trajectory."""
    from mcdm_pin.osim.motion import read_table
    from mcdm_pin.osim.rmr import RATE, frame_rows, frame_states, rmr_robot
    from mcdm_pin.trajectory import Trajectory

    robot = rmr_robot(motion.name)
    files = tuple(motion / f"Kinematics_{k}.sto" for k in ("q", "u", "dudt"))
    t = read_table(files[0]).time
    rows = frame_rows(files)
    rows = rows[np.isin(np.round(rows / RATE, 9), np.round(t, 9))] if len(t) < len(rows) else rows
    q, v, a = frame_states(robot, files, rows)
    return robot, Trajectory(name=motion.name, t=rows / RATE, q=q, qd=v, qdd=a)


def case_idents(robot, case: str):
    """``(label, {backend: InverseDynamics})``: ``1c`` RMR's problem with the cone, ``3`` case 3."""
    from mcdm_pin import InverseDynamics
    from mcdm_pin.osim.rmr import rmr_problem

    if case == "1c":
        problem = rmr_problem(robot, cone=True)
        return "RMR + cone", {n: InverseDynamics(robot, problem, solver=s) for n, s in BACKENDS}
    return "case 3", {n: InverseDynamics.for_case(robot, 3, solver=s) for n, s in BACKENDS}


def table(cases: list) -> str:
    lines = ["| problem | back-end | mode | model, ms | solve, ms | wall per frame, ms | vs ours | RMR / ours "
             "(p50) | no answer | check |", "|---|---|---|---|---|---|---|---|---|---|"]
    for c in cases:
        for mode in ("warm", "cold"):
            ours_wall = stats_ms(c["times"][("ours", mode)]["wall"])["median"]
            for name, _ in BACKENDS:
                r = c["times"][(name, mode)]
                wall = stats_ms(r["wall"])["median"]
                rmr = "-" if name != "ours" else f"{RMR_PER_FRAME_S[0] * 1e3 / wall:.0f}-{RMR_PER_FRAME_S[1] * 1e3 / wall:.0f}x"
                lines.append(f"| {c['case']} | {name} | {mode} | {_cell(r['model'])} | {_cell(r['solve'])} | "
                             f"{_cell(r['wall'])} | {'1' if name == 'ours' else f'{wall / ours_wall:.1f}x'} | "
                             f"{rmr} | {r['no_answer']} | {c['check'][name]} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--motion", default=str(DEFAULT_MOTION), help="folder of Kinematics_{q,u,dudt}.sto")
    p.add_argument("--case", nargs="+", default=["1c", "3"], choices=["1c", "3"])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--check", type=int, default=5)
    p.add_argument("--json")
    args = p.parse_args(argv)

    from threadpoolctl import threadpool_limits

    from mcdm_pin import jit

    t_start = time.perf_counter()
    load_start = os.getloadavg()[0]
    jit.prepare(policy="wait")
    cases = []
    with threadpool_limits(1):
        robot, traj = load(Path(args.motion))
        for case in args.case:
            label, idents = case_idents(robot, case)
            chk = check(idents, robot, traj, args.check)
            cases.append(dict(case=label, check=chk, times=time_case(idents, traj, args.repeat)))
    m = machine()
    print(f"{robot.name}: {robot.nv} DoF, {robot.m} muscles, {robot.n_act} actuators, a closed loop; motion "
          f"{traj.name} ({len(traj)} frames); {args.repeat} timed run(s) per back-end and mode; one BLAS thread.")
    print(f"Machine: {m['cpu']}, {m['nproc']} cores, Python {m['python']}; "
          + ", ".join(f"{k} {v}" for k, v in m["versions"].items()))
    print(f"1-min load average: {load_start:.2f} at the start, {m['load_avg_1min']:.2f} at the end (shared "
          f"machine); busiest processes at the end: {top_processes()}")
    print(f"Cells: p50 / p99 per frame, ms. RMR: {RMR_PER_FRAME_S[0]}-{RMR_PER_FRAME_S[1]} s per frame "
          f"(MATLAB fmincon + OpenSim, its own joint-reaction code, another machine).\n")
    print(table(cases))
    print(f"\n(ran {time.perf_counter() - t_start:.0f} s)")
    if args.json:
        out = dict(machine=m, cases=[dict(case=c["case"], check=c["check"], times={
            f"{k[0]}/{k[1]}": {p_: stats_ms(v) for p_, v in r.items() if p_ != "no_answer"}
            for k, r in c["times"].items()}) for c in cases])
        Path(args.json).write_text(json.dumps(out, indent=2))
    return 1 if any(c["check"]["ours"].startswith("FAIL") for c in cases) else 0


if __name__ == "__main__":
    sys.exit(main())
