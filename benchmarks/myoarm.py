"""MyoSuite's arm (38 DoF, 63 muscles over 101 wraps): per-instant time of mcdm-pin against Clarabel,
and of the model part against MuJoCo's own floor, on the same states.

    python benchmarks/myoarm.py [--robot robots/myosuite/myoarm.yaml] [--trajectory abduction]
        [--case 1 1c 3] [--repeat 3] [--check 5] [--json FILE]

On ``robots/myosuite/myoarm.yaml``'s ``abduction`` trajectory (101 instants), for case 1 (least
squared activations), ``1c`` (the same with the sidecar's stability cones: the glenohumeral question,
RMR's problem, docs/glenohumeral.md) and case 3 (interactions and stability cones; when the sidecar
gives no cone, case 3 is refused and case 2 is timed instead, with a note):

- **ours** (``InverseDynamics``, default solver chain) and **Clarabel** (the same problem through
  ``solver="clarabel"``) in the same run, their runs taken in turns so that a slow spell of the shared
  machine falls on both. *Warm*: ``solve_trajectory`` along the trajectory, after one untimed run
  (model and solve per instant from the result's timings), then ``solve`` per instant in order with
  the previous forces (the wall time of each frame: the state's checks, the model, the solve, the
  answer's check, the outputs and the result). *Cold*: every instant alone in a shuffled order after ``reset()``, the wall time of
  ``solve``. Cells: median and 99th percentile per instant, ms. A warm run's first frame has no
  previous answer (a cold frame in the warm column, which sets its p99): the warm frames after it
  are also given apart, and among them ours split by whether the instant's optimum is a face (not
  unique: the least-norm stage moves the answer along it; a third of the arm's frames in case 3).
- **check**: before timing, both back-ends on ``--check`` instants against Clarabel at 1e-11
  (``bench_id``'s check: objective, equation of motion, bounds, cones).
- **the model part's floor**: MuJoCo 4.0's ``mj_inverse`` (its position stage runs kinematics, the
  tendons with their wraps and moment arms, the inertia; then RNE for ``qfrc_inverse``), contacts
  disabled, on the same states, per frame; and ``mj_inverse`` + ``mj_rnePostConstraint`` (the
  interaction forces ``cfrc_int``). Ours: ``TermsEvaluator.__call__`` per frame (RNEA, tendon paths
  over the wraps, lengths, ``L``, the interaction-wrench maps, muscle bounds, couplings). Their passes
  over the trajectory are taken in turns, so that the ratio holds when the machine changes speed.

One BLAS thread throughout (threadpoolctl). The machine is shared: the 1-minute load average is
printed at the start and the end, with the processes that used the most CPU meanwhile.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import REPO, machine  # noqa: E402
from bench_id import check_solution, cold_instants, reference_solve, state, stats_ms  # noqa: E402

from mcdm_pin.solvers.least_norm import LeastNorm  # noqa: E402

DEFAULT_ROBOT = REPO / "robots" / "myosuite" / "myoarm.yaml"
BACKENDS = (("ours", "default"), ("clarabel", "clarabel"))
LEAST_NORM = LeastNorm.name  # (the stage that moves an answer along a face of optima: its name in `stage`)
SAMPLES = ("model", "solve", "wall", "total", "later", "later_face", "later_plain")  # (per run: time_warm's, time_cold's)


def load(robot_path: Path, trajectory: str, tmp: Path):
    """The robot, its trajectory and MuJoCo's compiled model of the same MJCF (contacts off)."""
    import mujoco

    from mcdm_pin import Robot, load_trajectory

    here = os.getcwd()
    os.chdir(tmp)  # MuJoCo writes MUJOCO_LOG.TXT where it runs
    try:
        robot = Robot.load(robot_path)
        mj = mujoco.MjModel.from_xml_path(str(robot.sidecar.mjcf_path))
    finally:
        os.chdir(here)
    mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    return robot, load_trajectory(robot, trajectory), mj


def case_idents(robot, case: str):
    """``(case timed, note, {backend: InverseDynamics})``: case 3 falls back to case 2 when refused;
    ``1c`` is case 1's objective with every cone of the sidecar."""
    from mcdm_pin import InverseDynamics
    from mcdm_pin.constraints import InteractionCone
    from mcdm_pin.exceptions import ProblemError
    from mcdm_pin.problem import Problem, case_problem

    note = ""
    if case == "1c":
        cones = [InteractionCone(j.name) for j in robot.joints if j.cone_deg is not None]
        problem = Problem(robot, case_problem(robot, 1).objective, cones)
        return "1 + cones", note, {name: InverseDynamics(robot, problem, solver=solver) for name, solver in BACKENDS}
    case = int(case)
    try:
        idents = {name: InverseDynamics.for_case(robot, case, solver=solver) for name, solver in BACKENDS}
    except ProblemError as exc:
        if case != 3:
            raise
        note = f"case 3 refused ({exc}): case 2 timed instead"
        case = 2
        idents = {name: InverseDynamics.for_case(robot, case, solver=solver) for name, solver in BACKENDS}
    return case, note, idents


def check(idents, robot, traj, n_check: int) -> dict:
    """Each back-end on ``n_check`` instants spread over the trajectory (in order, warm) against
    Clarabel at 1e-11: ``{backend: "ok" | "FAIL k/n" | "n/a"}``."""
    from mcdm_pin.problem import Context

    idx = np.unique(np.round(np.linspace(0, len(traj) - 1, min(n_check, len(traj)))).astype(int))
    out = {}
    for name, ident in idents.items():
        ident.reset()
        bad = judged = 0
        f_prev = None
        for k in idx:
            qp = ident.problem.assemble(ident.evaluate(*state(traj, k)), Context(robot))
            ref = reference_solve(qp)
            res = ident.solve(*state(traj, k), f_prev=f_prev)
            f_prev = res.f if res.found else f_prev
            if ref is None:
                continue
            x = np.concatenate([res.f, res.tau_act]) if res.found else None  # cables, then reserves
            ok, _ = check_solution(qp, x, qp.objective(ref))
            judged += 1
            bad += not ok
        out[name] = "n/a" if not judged else ("ok" if not bad else f"FAIL {bad}/{judged}")
    return out


def time_warm(ident, traj) -> dict:
    """``solve_trajectory`` (its model and solve timings per instant), then the same instants in
    order through ``solve`` with the previous forces, each timed whole (the frame: the state's
    checks, the model, the solve, the answer's check, the outputs and the result)."""
    res = ident.solve_trajectory(traj, progress=False)
    ok = res.found
    ident.reset()
    wall, face, f_prev = [], [], None
    for k in range(len(traj)):
        t0 = time.perf_counter()
        one = ident.solve(*state(traj, k), f_prev=f_prev)
        wall.append(time.perf_counter() - t0)
        face.append(LEAST_NORM in (one.stage or ""))
        f_prev = one.f if one.found else f_prev
    later, face = np.array(wall[1:]), np.array(face[1:])  # (the first frame has no previous answer: a cold one)
    return dict(model=res.time_model_s[ok], solve=res.time_solve_s[ok], wall=np.array(wall),
                total=(res.time_model_s + res.time_solve_s)[ok], no_answer=int((~ok).sum()),
                later=later, later_face=later[face], later_plain=later[~face])


def time_cold(ident, traj, order) -> dict:
    model, solve, wall, bad = cold_instants(ident, traj, order)
    return dict(model=model, solve=solve, wall=wall, total=wall, no_answer=bad)


def time_case(idents, traj, repeat: int, seed: int = 0) -> dict:
    """``{(backend, mode): {part: samples}}``, the back-ends' runs taken in turns."""
    rng = np.random.default_rng(seed)
    rec = {}
    for ident in idents.values():
        ident.reset()
        ident.solve_trajectory(traj, progress=False)  # untimed: imports, caches, warm CPU
    for _ in range(repeat):
        for mode in ("warm", "cold"):
            order = rng.permutation(len(traj))
            for name, ident in idents.items():
                ident.reset()
                one = time_warm(ident, traj) if mode == "warm" else time_cold(ident, traj, order)
                r = rec.setdefault((name, mode), dict({key: [] for key in SAMPLES}, no_answer=0))
                for key in SAMPLES:
                    if key in one:
                        r[key].append(one[key])
                r["no_answer"] += one["no_answer"]
    return {k: {p: (v if p == "no_answer" else np.concatenate(v) if v else np.zeros(0)) for p, v in r.items()}
            for k, r in rec.items()}


def time_floor(robot, traj, mj, repeat: int) -> dict:
    """Per frame, seconds: ours ``TermsEvaluator.__call__``; MuJoCo's ``mj_inverse`` and
    ``mj_inverse`` + ``mj_rnePostConstraint`` on the same states."""
    import mujoco

    from mcdm_pin.model.terms import TermsEvaluator

    ev = TermsEvaluator(robot, compiled=True)
    maps = robot.source.maps
    states = [state(traj, k) for k in range(len(traj))]
    mj_states = [(maps.to_mj_qpos(q), maps.to_mj_qvel(v, q), maps.to_mj_qvel(a, q)) for q, v, a in states]
    d = mujoco.MjData(mj)

    def ours(s):
        ev(*s, checked=True)

    def load_state(s):
        d.qpos[:], d.qvel[:], d.qacc[:] = s

    def inverse(s):
        load_state(s)
        mujoco.mj_inverse(mj, d)

    def inverse_cfrc(s):
        load_state(s)
        mujoco.mj_inverse(mj, d)
        mujoco.mj_rnePostConstraint(mj, d)

    def copy_only(s):
        load_state(s)

    runs = (("ours", ours, states), ("mj_inverse", inverse, mj_states),
            ("mj_inverse+rnePostConstraint", inverse_cfrc, mj_states), ("state copy", copy_only, mj_states))
    for _, fn, items in runs:
        for s in items:  # untimed pass
            fn(s)
    out = {name: [] for name, _, _ in runs}
    # the passes taken in turns (one pass of each, then the next round): a change of the shared
    # machine's speed falls on all four, and their ratio stays what it is
    for _ in range(repeat * 5):
        for name, fn, items in runs:
            ts = out[name]
            for s in items:
                t0 = time.perf_counter()
                fn(s)
                ts.append(time.perf_counter() - t0)
    return {name: np.array(ts) for name, ts in out.items()}


def time_parts(robot, traj, repeat: int) -> dict:
    """Per frame, seconds: the parts of ``TermsEvaluator.__call__`` one by one, on the same states
    (each part repeated on its own: the sum is not the whole, which also builds the result)."""
    import pinocchio as pin

    from mcdm_pin.model.terms import TermsEvaluator

    ev = TermsEvaluator(robot, compiled=True)
    model, data = ev.model, ev.data
    states = [state(traj, k) for k in range(len(traj))]
    last = {}

    def kinematics(s):
        pin.computeJointJacobians(model, data, s[0])
        last["oM"] = ev.placements()
        last["J"] = np.ascontiguousarray(data.J.reshape(6, -1).T)

    def routes(s):
        last["route"] = ev._routes(last["oM"])[0]

    def cable_terms(s):
        last["terms"] = ev._kernel(last["oM"], last["J"], last["route"], ev._kernel_args)

    def rnea(s):
        last["tau"] = pin.rnea(model, data, *s)

    def passive(s):
        if ev.passive is not None:
            ev.passive(s[0], s[1])

    def muscles(s):
        ev._tension_bounds(last["terms"][2], last["terms"][3], s[1])

    def couplings(s):
        if ev.couplings is not None:
            ev.couplings.project(s[0], last["terms"][3], last["tau"])

    parts = (("kinematics + Jacobians + placements", kinematics), ("routes (compiled wrap pass)", routes),
             ("cable_terms kernel (lengths, L, wrench maps)", cable_terms), ("rnea", rnea),
             ("joint springs and dampers (mjcf joint_passive)", passive), ("muscle bounds", muscles),
             ("couplings: N, L N and N^T tau", couplings))
    out = {name: [] for name, _ in parts}
    for rep in range(repeat * 5 + 1):
        for s in states:
            for name, fn in parts:
                t0 = time.perf_counter()
                fn(s)
                if rep:  # the first pass untimed
                    out[name].append(time.perf_counter() - t0)
    return {k: np.array(v) for k, v in out.items()}


def top_processes(n: int = 6) -> str:
    """The processes using the most CPU now (``ps``), this one excluded."""
    try:
        lines = subprocess.run(["ps", "-eo", "pid,pcpu,etime,comm", "--sort=-pcpu"], capture_output=True,
                               text=True, timeout=10).stdout.splitlines()[1:]
    except (OSError, subprocess.SubprocessError):
        return "(ps unavailable)"
    rows = [ln.split(None, 3) for ln in lines]
    rows = [r for r in rows if len(r) == 4 and int(r[0]) != os.getpid()][:n]
    return "; ".join(f"{r[3]} {r[1]}% (pid {r[0]})" for r in rows)


def _cell(x) -> str:
    s = stats_ms(x)
    return "-" if not s["n"] else f"{s['median']:.3f} / {s['p99']:.3f}"


def table(cases: list, floor: dict, parts: dict) -> str:
    lines = ["| case | back-end | mode | model, ms | solve, ms | model + solve, ms | wall per instant, ms "
             "| vs ours | no answer | check |", "|---|---|---|---|---|---|---|---|---|---|"]
    for c in cases:
        for mode in ("warm", "cold"):
            ours_wall = stats_ms(c["times"][("ours", mode)]["wall"])["median"]
            for name, _ in BACKENDS:
                r = c["times"][(name, mode)]
                ratio = stats_ms(r["wall"])["median"] / ours_wall
                lines.append(f"| {c['case']} | {name} | {mode} | {_cell(r['model'])} | {_cell(r['solve'])} | "
                             f"{_cell(r['total'])} | {_cell(r['wall'])} | "
                             f"{'1' if name == 'ours' else f'{ratio:.1f}x'} | {r['no_answer']} | "
                             f"{c['check'][name]} |")
    for c in cases:  # a warm run's first frame has no previous answer: it is a cold one
        later = ", ".join(f"{name} {_cell(c['times'][(name, 'warm')]['later'])}" for name, _ in BACKENDS)
        lines.append(f"\nCase {c['case']}, warm frames after each run's first (p50 / p99 wall, ms): {later}")
        ours = c["times"][("ours", "warm")]
        n_face, n_all = len(ours["later_face"]), len(ours["later"])
        lines.append(f"Case {c['case']}, ours, those frames whose optimum is a face (the least-norm stage moves the "
                     f"answer along it): {n_face} of {n_all}, {_cell(ours['later_face'])}; the others "
                     f"{_cell(ours['later_plain'])}")
    lines += ["", "| model part per frame | p50, ms | p99, ms | vs mj_inverse (p50) |", "|---|---|---|---|"]
    ref = stats_ms(floor["mj_inverse"])["median"]
    for name, x in floor.items():
        s = stats_ms(x)
        lines.append(f"| {name} | {s['median']:.4f} | {s['p99']:.4f} | {s['median'] / ref:.2f}x |")
    lines += ["", "| ours, by part (each timed alone) | p50, ms | p99, ms |", "|---|---|---|"]
    for name, x in parts.items():
        s = stats_ms(x)
        lines.append(f"| {name} | {s['median']:.4f} | {s['p99']:.4f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--robot", default=str(DEFAULT_ROBOT), help="MJCF sidecar (default: MyoSuite's arm)")
    p.add_argument("--trajectory", default="abduction")
    p.add_argument("--case", nargs="+", default=["1", "1c", "3"], choices=["1", "1c", "2", "3"])
    p.add_argument("--repeat", type=int, default=3, help="timed runs per back-end and mode (default 3)")
    p.add_argument("--check", type=int, default=5, help="instants checked against Clarabel at 1e-11")
    p.add_argument("--json", help="write the samples' statistics as JSON")
    args = p.parse_args(argv)

    from threadpoolctl import threadpool_limits

    from mcdm_pin import jit

    t_start = time.perf_counter()
    load_start = os.getloadavg()[0]
    jit.prepare(policy="wait")
    cases, notes = [], []
    with threadpool_limits(1), tempfile.TemporaryDirectory() as tmp:
        robot, traj, mj = load(Path(args.robot), args.trajectory, Path(tmp))
        for case in args.case:
            timed, note, idents = case_idents(robot, case)
            if note:
                notes.append(note)
            chk = check(idents, robot, traj, args.check)
            cases.append(dict(case=timed, check=chk, times=time_case(idents, traj, args.repeat)))
        floor = time_floor(robot, traj, mj, args.repeat)
        parts = time_parts(robot, traj, args.repeat)
    m = machine()
    print(f"{robot.name}: {robot.nv} DoF, {robot.m} cables, {len(robot.cables.wraps)} wraps; trajectory "
          f"{traj.name} ({len(traj)} instants); {args.repeat} timed run(s) per back-end and mode; one BLAS "
          f"thread.")
    print(f"Machine: {m['cpu']}, {m['nproc']} cores, Python {m['python']}; "
          + ", ".join(f"{k} {v}" for k, v in m["versions"].items()))
    print(f"1-min load average: {load_start:.2f} at the start, {m['load_avg_1min']:.2f} at the end (shared "
          f"machine); busiest processes at the end: {top_processes()}")
    for note in notes:
        print(f"note: {note}")
    print("Cells: p50 / p99 per instant, ms. Warm: solve_trajectory (model and solve from its timings), then "
          "solve() per instant in order with the previous forces (wall per frame: the whole call, with the "
          "state's checks, the answer's check, the outputs and the result). Cold: reset() then solve() per "
          "instant, shuffled (wall of solve). The model part's floor: mj_inverse computes no muscle forces; "
          "ours includes the muscles' bounds.\n")
    print(table(cases, floor, parts))
    print(f"\n(ran {time.perf_counter() - t_start:.0f} s)")
    if args.json:
        out = dict(machine=m, notes=notes, cases=[dict(case=c["case"], check=c["check"], times={
            f"{k[0]}/{k[1]}": {p_: stats_ms(v) for p_, v in r.items() if p_ != "no_answer"}
            for k, r in c["times"].items()}) for c in cases],
            floor={k: stats_ms(v) for k, v in floor.items()}, parts={k: stats_ms(v) for k, v in parts.items()})
        Path(args.json).write_text(json.dumps(out, indent=2))
    return 1 if any(c["check"]["ours"].startswith("FAIL") for c in cases) else 0


if __name__ == "__main__":
    sys.exit(main())
