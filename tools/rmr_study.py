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
import json
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from mcdm_pin.inverse_dynamics import InverseDynamics  # noqa: E402
from mcdm_pin.osim.motion import read_table  # noqa: E402
from mcdm_pin.osim.rmr import (GH, N_MUSCLES, RATE, frame_rows, frame_states, rmr_in_our_problem,  # noqa: E402
                               rmr_objective, rmr_problem, rmr_robot)
from mcdm_pin.problem import Context  # noqa: E402

REFERENCE = REPO.parent / "shared" / "reference" / "rmr"  # RMR's files beside the clone (../shared)
MOTIONS = ("abd01", "flx01", "shrug01")


def motion_files(motion: str, folder=None) -> tuple:
    folder = Path(folder) if folder is not None else REFERENCE / "motions" / motion
    return tuple(folder / f"Kinematics_{k}.sto" for k in ("q", "u", "dudt"))


def rmr_answer(motion: str, cone: bool) -> np.ndarray:
    """RMR's ``xsol`` (frames x 51) of a motion, with or without the glenohumeral constraint."""
    from scipy.io import loadmat

    sub = "with_GH" if cone else "without_GH"
    return loadmat(REFERENCE / "results" / sub / f"muscle_activations_Seth2019_experiment_{motion.upper()}.mat")["xsol"]


def run(motion: str, cone: bool, every: int = 1, solver: str = "default", files=None, rows=None) -> dict:
    """One motion and case: per-frame records and the summary (module docstring)."""
    robot = rmr_robot(motion)
    files = motion_files(motion) if files is None else files
    rows = frame_rows(files, every) if rows is None else np.asarray(rows)
    Q, V, A = frame_states(robot, files, rows)
    X = rmr_answer(motion, cone)
    ident = InverseDynamics(robot, rmr_problem(robot, cone), solver=solver)
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
            f"{s['rmr_cone_broken']} ({s['rmr_cone_max_deg']:.2f}) | "
            f"{s['ours_angle_max']:.2f} / {s['rmr_angle_max']:.2f} |")
    return "\n".join(lines)


def excerpt(motion: str, every: int, out: Path) -> None:
    """Write the excerpt committed under robots/opensim/motions: the rows of the motion's three tables
    that bracket RMR's frames ``0, every, 2 every, ...`` (interpolating them at those times gives the
    full tables' values) and RMR's ``xsol`` at those frames, with and without the cone (CSV)."""
    files = motion_files(motion)
    rows = frame_rows(files, 1)
    rows = rows[rows % every == 0]
    t = read_table(files[0]).time
    keep = sorted({int(i) for k in rows for i in (np.searchsorted(t, k / RATE, side="right") - 1,
                                                  np.searchsorted(t, k / RATE, side="left"))})
    out.mkdir(parents=True, exist_ok=True)
    for f in files:
        lines = f.read_text().splitlines()
        end = next(i for i, s in enumerate(lines) if s.strip().lower() == "endheader")
        head = [f"nRows={len(keep)}" if s.startswith("nRows=") else s for s in lines[:end + 2]]
        (out / f.name).write_text("\n".join(head + [lines[end + 2 + i] for i in keep]) + "\n")
    for cone in (False, True):
        X = rmr_answer(motion, cone)[rows]
        name = f"rmr_xsol_{'with' if cone else 'without'}_GH.csv"
        np.savetxt(out / name, np.column_stack([rows, X]), delimiter=",", fmt="%.10g",
                   header="frame (k / 100 s)," + ",".join(f"x{i}" for i in range(X.shape[1])))


EXCERPT = REPO / "robots" / "opensim" / "motions" / "abd01"  # the committed excerpt: every 5th frame


def check_excerpt() -> int:
    """The committed ABD01 excerpt is what :func:`excerpt` writes from RMR's files (byte for byte), and
    the states it gives at three frames (arm low, rising, high) equal the full tables'."""
    import filecmp
    import tempfile

    from mcdm_pin.osim.rmr import rmr_robot

    with tempfile.TemporaryDirectory() as tmp:
        excerpt("abd01", 5, Path(tmp))
        differ = [f.name for f in sorted(Path(tmp).iterdir()) if not filecmp.cmp(f, EXCERPT / f.name, shallow=False)]
    robot, rows = rmr_robot("abd01"), (100, 450, 700)
    ours = frame_states(robot, motion_files("abd01", EXCERPT), rows)
    full = frame_states(robot, motion_files("abd01"), rows)
    same = all(np.array_equal(a, b) for a, b in zip(ours, full))
    print(f"excerpt: {len(differ)} file(s) differ from a regeneration{': ' + ', '.join(differ) if differ else ''}; "
          f"states at frames {rows} {'equal' if same else 'DIFFER from'} the full motion's")
    return 0 if not differ and same else 1


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check-excerpt", action="store_true",
                    help="only check the committed ABD01 excerpt against RMR's files (needs ../shared)")
    ap.add_argument("--every", type=int, default=1, help="every K-th frame (default: all, 100 Hz)")
    ap.add_argument("--motions", default=",".join(MOTIONS))
    ap.add_argument("--json", default=None, help="write the per-frame records here")
    args = ap.parse_args(argv)
    if args.check_excerpt:
        return check_excerpt()
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
