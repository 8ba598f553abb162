"""RMR's shoulder study on our solver: the thoracoscapular model (robots/opensim/tsm_rmr.yaml), the three
measured motions (ABD01, FLX01, SHRUG01) at 100 Hz, with and without the glenohumeral cone, against the
RMR solver's answers (Belli et al., PLOS ONE 2023; data CC BY 4.0 in ../shared/reference/rmr).

    PYTHONPATH=. python tools/rmr_study.py [--every K] [--motions abd01,flx01] [--states rmr|cmc]
                                           [--json out.json] [--plot fig.png] [--reference DIR]
    PYTHONPATH=. python tools/rmr_study.py --audit [--every K]     # RMR's constraint in OpenSim
    PYTHONPATH=. python tools/rmr_study.py --check-excerpt         # the committed ABD01 excerpt

Per motion and case: frames solved (status counts); our objective ``sum a^2 + sum w c^2`` against RMR's
at RMR's answer (``xsol``: 33 activations, then the 17 CoordinateActuators' controls in the model's
actuator order; its 51st column, the mean of the three serratus anterior activations that RMR appended
afterwards, is left out); how far RMR's answer is from our constraints (equation of motion, activation
bounds, cone); the activation RMSE; and, on a common footing, RMR's answer closed onto our feasible set
(``rmr.close_answer``) against our optimum, which must never be higher.

Which problem runs: each frame on its own (a global optimum per frame; RMR's inter-frame
activation-dynamics bounds are not imposed), at RMR's own states by default (its IK solution low-passed
at 3 Hz and differentiated twice, ``rmr.rmr_states``; frame k at k / 100 s, from 0) with RMR's force
model (``rmr.rmr_robot``: no fibre damping), or at CMC's tables (``--states cmc``). In SHRUG01 RMR frees
the accelerations of plane_elv and axial_rot; here their actuators weigh 0 (free torques at the measured
accelerations), the one difference left; ``eom_freed`` reports RMR's residual with those accelerations
free. ``--audit`` (tools/rmr_opensim.py) evaluates RMR's answers in OpenSim as RMR's code does.
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
from mcdm_pin.osim.rmr import (GH, N_MUSCLES, RATE, SHRUG_FREED, close_answer, frame_rows,  # noqa: E402
                               frame_states, rmr_exact_objective, rmr_in_our_problem, rmr_objective, rmr_problem,
                               rmr_robot, rmr_socp, rmr_states)
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


def run(motion: str, cone: bool, every: int = 1, solver: str = "default", files=None, rows=None,
        states: str = "rmr") -> dict:
    """One motion and case: per-frame records and the summary (module docstring). ``states``: ``rmr``
    (RMR's filtered IK, every frame of ``xsol``) or ``cmc`` (CMC's tables, ``files``)."""
    robot = rmr_robot(motion)
    X = rmr_answer(motion, cone)
    if states == "rmr":
        rows = np.arange(0, len(X), every) if rows is None else np.asarray(rows)
        Q, V, A = rmr_states(robot, motion, rows)
    else:
        files = motion_files(motion) if files is None else files
        rows = frame_rows(files, every) if rows is None else np.asarray(rows)
        Q, V, A = frame_states(robot, files, rows)
    ident = InverseDynamics(robot, rmr_problem(robot, cone), solver=solver)
    frames = []
    for row, q, v, a in zip(rows, Q, V, A):
        t0 = time.perf_counter()
        res = ident.solve(q, v, a)
        dt = time.perf_counter() - t0
        terms = ident.evaluate(q, v, a)
        qp = ident.problem.assemble(terms, Context(robot))
        freed = SHRUG_FREED if motion.startswith("shrug") else ()
        theirs = rmr_in_our_problem(ident, terms, qp, X[row], freed) if row < len(X) else None
        ours_a = res.activation[robot.cables.muscle_index] if res.found else np.full(N_MUSCLES, np.nan)
        if theirs is not None:
            theirs["exact"] = exact_problem(robot, terms, qp, X[row], freed)
        frames.append(dict(row=int(row), status=res.status, objective=float(res.objective), time_s=dt,
                           angle_deg=float(res.interaction_angle_deg[robot.joint_names.index(GH)]),
                           rmr_objective=rmr_objective(robot, X[row]) if row < len(X) else float("nan"),
                           rmse=float(np.sqrt(np.mean((ours_a - X[row, :N_MUSCLES]) ** 2))) if row < len(X)
                           else float("nan"), rmr=theirs))
    return dict(motion=motion, cone=cone, states=states, frames=frames, summary=summarise(frames))


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
                time_p50_ms=float(np.median(arr("time_s")) * 1e3), **closed_summary(ours, rmr))


def exact_problem(robot, terms, qp, x, freed) -> dict:
    """RMR's exact problem at this frame (``rmr.rmr_socp``: RMR's weights, in a shrug its freed
    accelerations), solved by Clarabel, and RMR's answer closed onto it: the objectives (RMR's own)."""
    z = rmr_socp(robot, terms, qp, None, freed)
    c = close_answer(robot, terms, qp, x, freed)
    return dict(optimum=rmr_exact_objective(z), closed=rmr_exact_objective(c), rmr=rmr_exact_objective(x),
                change=float(np.linalg.norm(c - x[:len(c)])))


def exact_table(results) -> str:
    """RMR's exact problem (markdown): its optimum against RMR's answer closed onto it."""
    lines = ["| motion | cone | frames | optimum mean J | RMR closed mean J | RMR raw mean J | distance p50/max | "
             "optimum > RMR closed | (closed - optimum) / closed, p50 / max | ours - optimum, max |",
             "|" + "---|" * 10]
    for r in results:
        fr = [f for f in r["frames"] if f["rmr"] is not None and f["status"] == "optimal"]
        if not fr:
            continue
        ex = lambda key: np.array([f["rmr"]["exact"][key] for f in fr])  # noqa: E731
        opt, closed, gap = ex("optimum"), ex("closed"), (ex("closed") - ex("optimum")) / ex("closed")
        ours = np.array([f["objective"] for f in fr])
        diff = "-" if r["motion"].startswith("shrug") else f"{np.nanmax(np.abs(ours - opt)):.1e}"
        lines.append(f"| {r['motion'].upper()} | {'with GH' if r['cone'] else 'without'} | {len(fr)} | "
                     f"{np.nanmean(opt):.4f} | {np.nanmean(closed):.4f} | {np.nanmean(ex('rmr')):.4f} | "
                     f"{np.nanmedian(ex('change')):.3g} / {np.nanmax(ex('change')):.3g} | "
                     f"{int(np.sum(opt > closed * (1 + 1e-6) + 1e-9))} | {np.nanmedian(gap):.2%} / {np.nanmax(gap):.2%} | "
                     f"{diff} |")
    return "\n".join(lines)


FEASIBLE = 1e-6  # activation-bound excess (1) and cone excess (deg) below which a closed answer counts as feasible


def closed_summary(ours, rmr) -> dict:
    """RMR's answers completed by the least change that closes our equation (rmr.close_answer): at how
    many frames they are feasible (bounds, cone), the change's size, and ours against their objective
    there (ours is the global optimum, so it must never be higher)."""
    ok = (rmr("closed_bounds") <= FEASIBLE) & (rmr("closed_cone_deg") <= FEASIBLE) & (rmr("closed_eom_rel") <= 1e-8)
    J = rmr("closed_objective")
    return dict(closed_feasible=int(ok.sum()), closed_change_p50=float(np.median(rmr("closed_change"))),
                closed_change_max=float(rmr("closed_change").max()),
                closed_ours_higher=int(np.sum(ok & (ours > J * (1 + 1e-6) + 1e-9))),
                closed_gap_p50=float(np.median((J[ok] - ours[ok]) / J[ok])) if ok.any() else float("nan"),
                closed_gap_max=float(np.max((J[ok] - ours[ok]) / J[ok])) if ok.any() else float("nan"),
                rmr_eom_raw_p50=float(np.median(rmr("eom_raw"))), rmr_eom_raw_max=float(rmr("eom_raw").max()),
                rmr_eom_freed_p50=float(np.median(rmr("eom_freed"))), rmr_eom_freed_max=float(rmr("eom_freed").max()))


def closed_table(results) -> str:
    """The common-footing table (markdown): RMR's answers closed onto our equation of motion."""
    head = ("| motion | cone | frames | RMR residual, own controls p50/max (N m) | the same, RMR's freed "
            "accelerations free | distance to our feasible set p50/max | closed RMR feasible | ours > closed RMR | "
            "(closed RMR J - ours J) / closed RMR J, p50 / max |")
    lines = [head, "|" + "---|" * 9]
    for r in results:
        s = r["summary"]
        if "ours_mean" not in s:
            continue
        lines.append(
            f"| {r['motion'].upper()} | {'with GH' if r['cone'] else 'without'} | {s['frames']} | "
            f"{s['rmr_eom_raw_p50']:.3g} / {s['rmr_eom_raw_max']:.3g} | "
            f"{s['rmr_eom_freed_p50']:.3g} / {s['rmr_eom_freed_max']:.3g} | "
            f"{s['closed_change_p50']:.3g} / {s['closed_change_max']:.3g} | {s['closed_feasible']} | "
            f"{s['closed_ours_higher']} | {s['closed_gap_p50']:.2%} / {s['closed_gap_max']:.2%} |")
    return "\n".join(lines)


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


def plot(results, path) -> None:
    """Per frame of one motion, without and with the cone: our objective, RMR's at its answer and at its
    answer closed onto our equation (feasible frames), and RMR's residual in our equation."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(results), figsize=(6 * len(results), 6), sharex=True, squeeze=False)
    for col, r in enumerate(results):
        fr = [f for f in r["frames"] if f["rmr"] is not None]
        t = np.array([f["row"] for f in fr]) / RATE
        ok = np.array([f["rmr"]["closed_bounds"] <= FEASIBLE and f["rmr"]["closed_cone_deg"] <= FEASIBLE for f in fr])
        ax = axes[0, col]
        ax.plot(t, [f["objective"] for f in fr], "k-", lw=1, label="ours (global optimum)")
        ax.plot(t, [f["rmr_objective"] for f in fr], "C0-", lw=0.8, label="RMR at its answer")
        closed = np.array([f["rmr"]["closed_objective"] for f in fr])
        ax.plot(t[ok], closed[ok], "C1.", ms=2, label="RMR closed onto our equation (feasible)")
        ax.set_title(f"{r['motion'].upper()} {'with GH' if r['cone'] else 'without GH'}")
        ax.set_ylabel("objective")
        ax.legend(fontsize=7)
        ax = axes[1, col]
        ax.semilogy(t, [f["rmr"]["eom_raw"] for f in fr], "C3-", lw=0.8)
        ax.set_ylabel("RMR's residual in our equation (N m)")
        ax.set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


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
    ap.add_argument("--states", choices=("rmr", "cmc"), default="rmr",
                    help="RMR's filtered IK (default, RMR's own states) or CMC's Kinematics tables")
    ap.add_argument("--audit", action="store_true",
                    help="only RMR's answers in OpenSim (its own constraint, our residual's origin; needs opensim)")
    ap.add_argument("--plot", default=None, help="write the per-frame figure of the first motion here (PNG)")
    ap.add_argument("--reference", default=None, help="RMR's folder (default ../shared/reference/rmr)")
    args = ap.parse_args(argv)
    global REFERENCE
    REFERENCE = Path(args.reference) if args.reference else REFERENCE
    if args.check_excerpt:
        return check_excerpt()
    if args.audit:
        from rmr_opensim import audit, audit_table

        print(audit_table([audit(m, c, rmr_answer(m, c), args.every) for m in args.motions.split(",")
                           for c in (False, True)]))
        return 0
    results = []
    for motion in args.motions.split(","):
        for cone in (False, True):
            t0 = time.perf_counter()
            results.append(run(motion, cone, args.every, states=args.states))
            print(f"{motion} cone={cone}: {len(results[-1]['frames'])} frames in {time.perf_counter() - t0:.1f} s",
                  file=sys.stderr)
    print(table(results))
    print()
    print(closed_table(results))
    print()
    print(exact_table(results))
    if args.plot:
        plot(results[:2], args.plot)
    if args.json:
        Path(args.json).write_text(json.dumps(results, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
