"""RMR's shoulder study on our solver: the thoracoscapular model (robots/opensim/tsm_rmr.yaml), the three
measured motions (ABD01, FLX01, SHRUG01) at 100 Hz, with and without the glenohumeral cone, against the
RMR solver's answers (Belli et al., PLOS ONE 2023; data CC BY 4.0 in ../shared/reference/rmr).

    PYTHONPATH=. python tools/rmr_study.py [--every K] [--motions abd01,flx01] [--json out.json]

Per motion and case: frames solved (status counts); our objective ``sum a^2 + sum w c^2`` against RMR's
at RMR's answer (``xsol``: 33 activations, then the 17 CoordinateActuators' controls in the model's
order; its 51st column matches no actuator of the model and is left out); how far RMR's answer is from
our constraints at our states (equation of motion, activation bounds, cone); and the activation RMSE.

Which problem runs: each frame on its own (a global optimum per frame). RMR couples frames through
activation-dynamics bounds (10 ms activation, 40 ms deactivation) and solves the accelerations of
filtered IK coordinates (3 Hz low-pass, finite differences); we take the motions' coordinates, speeds
and accelerations as CMC wrote them (Kinematics_{q,u,dudt}.sto), sampled at RMR's 100 Hz frame times
(frame k at k / 100 s, from 0). RMR's answers therefore satisfy RMR's equation, not ours, to the
accuracy this tool reports. In SHRUG01 RMR frees the accelerations of plane_elv and axial_rot (poorly
defined with the arm hanging); here their actuators weigh 0 (free), in both objectives.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from mcdm_pin.constraints import InteractionCone  # noqa: E402
from mcdm_pin.inverse_dynamics import InverseDynamics  # noqa: E402
from mcdm_pin.model.cables import CableSet  # noqa: E402
from mcdm_pin.model.muscles_osim import OpenSimMuscles  # noqa: E402
from mcdm_pin.objectives import MinActivations  # noqa: E402
from mcdm_pin.osim.document import read_osim  # noqa: E402
from mcdm_pin.osim.motion import motion_states, read_table  # noqa: E402
from mcdm_pin.problem import Context, Problem  # noqa: E402
from mcdm_pin.robot import Robot  # noqa: E402
from mcdm_pin.solvers.base import cone_violation_deg  # noqa: E402

SIDECAR = REPO / "robots" / "opensim" / "tsm_rmr.yaml"
OSIM = REPO / "robots" / "opensim" / "TSM_subject_noWeight.osim"
REFERENCE = REPO.parents[1] / "shared" / "reference" / "rmr"
MOTIONS = ("abd01", "flx01", "shrug01")
RATE = 100.0  # Hz, RMR's frames
N_MUSCLES, N_ACTUATORS = 33, 17
SHRUG_FREE = ("plane_elv_actuator", "axial_rot_actuator")
GH = "GlenoHumeral"


def rmr_robot(motion: str = "abd01", sidecar=SIDECAR) -> Robot:
    """The TSM as RMR poses it: activations in [0, 1] (RMR's bounds: it overrides the muscles' force,
    so the model's ``minimum_activation`` 0.01 does not apply); for a shrug, plane_elv's and
    axial_rot's actuators weigh 0."""
    robot = Robot.load(sidecar)
    cables = robot.cables
    muscles = OpenSimMuscles([dataclasses.replace(m, a_min=0.0) for m in cables.muscles.muscles])
    cables = CableSet(robot.model, cables.cables, muscles=muscles, muscle_cables=muscles.names)
    acts = robot.actuators
    if motion.startswith("shrug"):
        acts = tuple(dataclasses.replace(a, weight=0.0) if a.label in SHRUG_FREE else a for a in acts)
    return Robot(robot.model, cables, robot.joints, acts, robot.name, sidecar=robot.sidecar,
                 couplings=robot.couplings, coordinate_names=robot.coordinate_names, source=robot.source,
                 notes=robot.notes)


def motion_files(motion: str, folder=None) -> tuple:
    folder = Path(folder) if folder is not None else REFERENCE / "motions" / motion
    return tuple(folder / f"Kinematics_{k}.sto" for k in ("q", "u", "dudt"))


def frame_rows(files, every: int = 1) -> np.ndarray:
    """RMR's frame indices (``k / RATE`` s) inside the motion's time span, every ``every``-th."""
    t = read_table(files[0]).time
    k = np.arange(int(np.ceil(t[0] * RATE - 1e-9)), int(np.floor(t[-1] * RATE + 1e-9)) + 1)
    return k[::every]


def states(robot, files, rows):
    """(q, v, a) arrays at RMR's frames ``rows``."""
    return motion_states(robot.source, read_osim(OSIM), *files, np.asarray(rows) / RATE)


def rmr_answer(motion: str, cone: bool) -> np.ndarray:
    """RMR's ``xsol`` (frames x 51) of a motion, with or without the glenohumeral constraint."""
    from scipy.io import loadmat

    sub = "with_GH" if cone else "without_GH"
    return loadmat(REFERENCE / "results" / sub / f"muscle_activations_Seth2019_experiment_{motion.upper()}.mat")["xsol"]


def problem(robot, cone: bool) -> Problem:
    """RMR's objective (activations, the actuators' ``w c^2`` added by the problem), and the cone."""
    return Problem(robot, MinActivations(), [InteractionCone(GH)] if cone else [])


def actuator_weights(robot) -> tuple:
    """``(F_opt, w)`` per actuator: the torque is ``F_opt c``, the objective's term ``w c^2``."""
    f_opt = np.array([float(a.tau_max[0]) for a in robot.actuators]) / 1e4  # CONTROL_CAP
    return f_opt, np.array([a.weight for a in robot.actuators]) * f_opt ** 2


def rmr_objective(robot, xrow) -> float:
    """RMR's objective at its answer: ``sum a^2 + sum w c^2`` (our weights, RMR's values)."""
    _, w = actuator_weights(robot)
    x = np.asarray(xrow, dtype=float)
    return float(np.sum(x[:N_MUSCLES] ** 2) + np.sum(w * x[N_MUSCLES:N_MUSCLES + N_ACTUATORS] ** 2))


def rmr_in_our_problem(ident, terms, qp, xrow) -> dict:
    """RMR's answer as our unknowns ``[f; tau]`` at our state and how far it is from our constraints:
    the equation of motion's residual (largest generalized force, N m or N, and relative), the
    activation bounds, the cone (degrees beyond it). The actuators that weigh nothing (the thorax's,
    the forearm's; in a shrug also plane_elv's and axial_rot's) are free in both problems: their
    torques are refitted to our state (least squares on the residual), which changes no objective."""
    robot = ident.robot
    x = np.asarray(xrow, dtype=float)
    st = terms.muscles
    k = robot.cables.muscle_index
    f = np.zeros(robot.m)
    f[k] = st.passive + st.gain * x[:N_MUSCLES]
    f_opt, _ = actuator_weights(robot)
    tau = f_opt * x[N_MUSCLES:N_MUSCLES + N_ACTUATORS]
    y = np.concatenate([f, tau])
    n = terms.tau.shape[0]
    free = robot.m + np.flatnonzero(np.array([a.weight for a in robot.actuators]) == 0.0)
    r = qp.A[:n] @ y - qp.b[:n]
    y[free] -= np.linalg.lstsq(qp.A[:n, free], r, rcond=None)[0]
    r = qp.A[:n] @ y - qp.b[:n]
    scale = max(np.abs(terms.tau).max(), 1e-300)
    cone = float(cone_violation_deg(qp, y).max(initial=0.0)) if qp.cones else 0.0
    a = x[:N_MUSCLES]
    return dict(eom_abs=float(np.abs(r).max()), eom_rel=float(np.abs(r).max() / scale),
                bounds=float(max((st.a_min - a).max(), (a - st.a_max).max(), 0.0)), cone_deg=cone,
                angle_deg=float(np.degrees(np.arccos(np.clip(
                    _cos(terms.wrenches(y)[robot.joint_names.index(GH), :3], robot, terms), -1, 1)))))


def _cos(F_child, robot, terms) -> float:
    j = robot.joint_names.index(GH)
    F = terms.R_socket[j] @ F_child
    return float(F @ terms.socket_axes[j] / max(np.linalg.norm(F), 1e-300))


def run(motion: str, cone: bool, every: int = 1, solver: str = "default", files=None, rows=None) -> dict:
    """One motion and case: per-frame records and the summary (module docstring)."""
    robot = rmr_robot(motion)
    files = motion_files(motion) if files is None else files
    rows = frame_rows(files, every) if rows is None else np.asarray(rows)
    Q, V, A = states(robot, files, rows)
    X = rmr_answer(motion, cone)
    ident = InverseDynamics(robot, problem(robot, cone), solver=solver)
    frames = []
    for row, q, v, a in zip(rows, Q, V, A):
        t0 = time.perf_counter()
        res = ident.solve(q, v, a)
        dt = time.perf_counter() - t0
        terms = ident.evaluate(q, v, a)
        qp = ident.problem.assemble(terms, Context(robot))
        theirs = rmr_in_our_problem(ident, terms, qp, X[row]) if row < len(X) else None
        ours_a = res.activation[robot.cables.muscle_index] if res.found else np.full(N_MUSCLES, np.nan)
        frames.append(dict(row=int(row), status=res.status, objective=float(res.objective), time_s=dt,
                           angle_deg=float(res.interaction_angle_deg[robot.joint_names.index(GH)]),
                           rmr_objective=rmr_objective(robot, X[row]) if row < len(X) else float("nan"),
                           rmse=float(np.sqrt(np.mean((ours_a - X[row, :N_MUSCLES]) ** 2))) if row < len(X)
                           else float("nan"), rmr=theirs))
    return dict(motion=motion, cone=cone, frames=frames, summary=summarise(frames))


def summarise(frames) -> dict:
    status = {}
    for f in frames:
        status[f["status"]] = status.get(f["status"], 0) + 1
    ok = [f for f in frames if f["status"] == "optimal" and f["rmr"] is not None]
    arr = lambda key: np.array([f[key] for f in ok])  # noqa: E731
    rmr = lambda key: np.array([f["rmr"][key] for f in ok])  # noqa: E731
    if not ok:
        return dict(status=status)
    ours, theirs = arr("objective"), arr("rmr_objective")
    return dict(status=status, frames=len(frames), ours_mean=float(ours.mean()), rmr_mean=float(theirs.mean()),
                ours_higher=int(np.sum(ours > theirs * (1 + 1e-6))),
                rmse_mean=float(arr("rmse").mean()), rmse_max=float(arr("rmse").max()),
                rmr_eom_abs_p50=float(np.median(rmr("eom_abs"))), rmr_eom_abs_max=float(rmr("eom_abs").max()),
                rmr_eom_rel_p50=float(np.median(rmr("eom_rel"))),
                rmr_cone_broken=int(np.sum(rmr("cone_deg") > 1e-6)), rmr_cone_max_deg=float(rmr("cone_deg").max()),
                rmr_angle_max=float(rmr("angle_deg").max()), ours_angle_max=float(arr("angle_deg").max()),
                time_p50_ms=float(np.median(arr("time_s")) * 1e3))


def table(results) -> str:
    """The study table (markdown)."""
    head = ("| motion | cone | frames | status | ours mean J | RMR mean J | ours > RMR | act. RMSE mean/max | "
            "RMR eom residual p50/max (N m) | RMR cone broken (max deg) | GH angle max ours/RMR (deg) |")
    lines = [head, "|" + "---|" * 11]
    for r in results:
        s = r["summary"]
        st = ", ".join(f"{k} {v}" for k, v in sorted(s["status"].items()))
        if "ours_mean" not in s:
            lines.append(f"| {r['motion']} | {'GH' if r['cone'] else '-'} | {len(r['frames'])} | {st} |" + " |" * 7)
            continue
        lines.append(
            f"| {r['motion'].upper()} | {'with GH' if r['cone'] else 'without'} | {s['frames']} | {st} | "
            f"{s['ours_mean']:.4f} | {s['rmr_mean']:.4f} | {s['ours_higher']} | "
            f"{s['rmse_mean']:.4f} / {s['rmse_max']:.4f} | {s['rmr_eom_abs_p50']:.3g} / {s['rmr_eom_abs_max']:.3g} | "
            f"{s['rmr_cone_broken']} ({s['rmr_cone_max_deg']:.2f}) | {s['ours_angle_max']:.2f} / {s['rmr_angle_max']:.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=1, help="every K-th frame (default: all, 100 Hz)")
    ap.add_argument("--motions", default=",".join(MOTIONS))
    ap.add_argument("--json", default=None, help="write the per-frame records here")
    args = ap.parse_args(argv)
    results = []
    for motion in args.motions.split(","):
        for cone in (False, True):
            t0 = time.perf_counter()
            results.append(run(motion, cone, args.every))
            print(f"{motion} cone={cone}: {len(results[-1]['frames'])} frames in {time.perf_counter() - t0:.1f} s",
                  file=sys.stderr)
    print(table(results))
    if args.json:
        Path(args.json).write_text(json.dumps(results, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
