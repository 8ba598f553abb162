"""``mcdm-pin solve ROBOT.yaml --trajectory NAME ...``: cable forces along a trajectory (cases 1-3)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..settings import DEFAULT, Settings
from ..vocabulary import CASES, CONE_FRAMES, FLAT_OBJECTIVE_STAGE
from ._common import UsageError, check_outputs, parse_cones, parse_weights, printable, table
from ._files import robot_file
from .view import html_file, solve_html_hook


def add(sub):
    p = sub.add_parser("solve", help="cable forces along a trajectory (cases 1-3)")
    p.add_argument("robot", help="cable sidecar (YAML) or MuJoCo MJCF file")
    p.add_argument("--trajectory", "-t", required=True, help="a trajectory named in the sidecar")
    p.add_argument("--case", type=int, choices=CASES, default=1,
                   help="1: min f^T f; 2: min interactions; 3: case 2 + stability cones (default 1)")
    p.add_argument("--weights", help="alpha (and beta) per joint: JOINT=ALPHA[:BETA],...")
    p.add_argument("--cone", help="cone half-angle per joint: JOINT=DEG,... or all=DEG (case 3)")
    p.add_argument("--frame", choices=CONE_FRAMES, default="socket",
                   help="frame of the cone's force (default socket, the source paper's)")
    p.add_argument("--solver", default="default",
                   help="default (the compiled active set and interior-point method, ProxQP and "
                        "Clarabel as fallbacks), or one method alone: compiled, proxqp, clarabel "
                        "(the exact reference)")
    p.add_argument("--budget", type=float, default=DEFAULT.budget_s, metavar="SECONDS",
                   help=f"time budget per instant (default {DEFAULT.budget_s:g} s): an instant not solved by then is "
                        "reported with status 'budget'")
    p.add_argument("--samples", type=int, help="solve N instants spread over the trajectory")
    p.add_argument("--smoothing", type=float, default=0.0, help="weight of |f - f_prev|^2 (default 0)")
    p.add_argument("--soften", action="store_true",
                   help="where the cones cannot be met, return the least-violating forces (flagged)")
    p.add_argument("--out", action="append", default=[], help="write results (.npz or .csv); repeatable")
    p.add_argument("--no-diagnosis", action="store_true",
                   help="do not analyse infeasible instants (what conflicts, the f_max or cone angle "
                        "that would do); faster when many instants are infeasible")
    p.add_argument("--workers", type=int, default=1,
                   help="processes for batch mode (default 1; results equal the sequential run's "
                        "to solver tolerance; not with --smoothing)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    p.add_argument("--html", type=html_file, metavar="FILE.html",
                   help="also write the 3-D view of the result as one self-contained HTML file")
    p.set_defaults(func=run)
    return p


def run_solve(args):
    """Build and run the problem from parsed ``solve`` arguments; return (robot, result)."""
    from ..inverse_dynamics import InverseDynamics
    from ..robot import Robot
    from ..trajectory import load_trajectory

    robot = Robot.load(robot_file(args.robot))
    _check_outputs(args, robot)
    if args.samples is not None and args.samples < 1:
        raise UsageError(f"--samples: expected a positive number, got {args.samples}")
    if not np.isfinite(args.smoothing) or args.smoothing < 0:
        raise UsageError(f"--smoothing: expected a weight >= 0, got {args.smoothing}")
    alpha, beta = parse_weights(robot, args.weights)
    cones = parse_cones(robot, args.cone)
    if cones and args.case != 3:
        raise UsageError("--cone applies to --case 3 only")
    traj = load_trajectory(robot, args.trajectory)
    if args.samples:
        traj = traj.subsample(args.samples)
    from ..problem import case_problem
    problem = case_problem(robot, args.case, alpha=alpha, beta=beta, cones=cones, frame=args.frame,
                           smoothing=args.smoothing)
    if not args.budget > 0:
        raise UsageError(f"--budget: expected a positive number of seconds, got {args.budget}")
    ident = InverseDynamics(robot, problem, solver=args.solver, soften=args.soften,
                            diagnose=not args.no_diagnosis, settings=Settings(budget_s=args.budget))
    if args.workers < 1:
        raise UsageError(f"--workers: expected a positive number, got {args.workers}")
    result = ident.solve_trajectory(traj, progress=False if args.quiet else None, workers=args.workers)
    result.problem = f"case {args.case}: " + result.problem
    return robot, result


def _check_outputs(args, robot) -> None:
    """Every output path checked before solving (a run must not be lost at the end), never an input."""
    inputs = [("the sidecar", robot.sidecar.path), ("the URDF", robot.urdf_path)]
    spec = robot.sidecar.trajectories.get(args.trajectory)
    if spec is not None and spec.type == "csv":
        inputs.append((f"trajectory {args.trajectory!r}'s CSV", spec.file))
    outs = [("--out", o) for o in args.out] + ([("--html", args.html)] if getattr(args, "html", None) else [])
    check_outputs(outs, inputs)


def run(args) -> int:
    for out in args.out:
        if Path(out).suffix not in (".npz", ".csv"):
            raise UsageError(f"--out: expected a .npz or .csv file name, got {out!r}")
    robot, result = run_solve(args)
    print(summary(result))
    for out in args.out:
        path = result.save(out)
        print(f"wrote {path}")
    solve_html_hook(args, robot, result)
    return 0


def _peak(col) -> int:
    """The instant of the largest finite value of ``col``: the first one within 1e-9 (relative) of
    it, so that a tie to rounding (a symmetric trajectory's two equal peaks) reports the same
    instant whatever the last bits of the answers."""
    k = int(np.nanargmax(col))
    with np.errstate(invalid="ignore"):
        return int(np.flatnonzero(col >= col[k] - 1e-9 * abs(col[k]))[0])


def summary(result) -> str:
    """The solve summary: peaks per cable and joint, infeasible instants, timing."""
    t = result.t
    lines = [f"{result.robot}: {result.problem}",
             f"trajectory {result.trajectory}: {len(t)} instants, t = {t[0]:g}..{t[-1]:g} s, "
             f"solver {result.solver}"]
    found = result.found
    rows = []
    for i, name in enumerate(result.cable_names):
        col = result.f[:, i]
        if np.any(np.isfinite(col)):
            k = _peak(col)
            rows.append([name, f"{col[k]:.4f}", f"{t[k]:.3f}", f"{np.nanmin(col):.4f}"])
        else:
            rows.append([name, "-", "-", "-"])
    lines += ["", table(["cable", "peak f N", "at t s", "min f N"], rows)]
    rows = []
    Fmag = result.force_magnitude
    types = list(result.joint_types) if result.joint_types is not None else ["spherical"] * len(result.joint_names)
    for j, name in enumerate(result.joint_names):
        if np.any(np.isfinite(Fmag[:, j])):
            k = _peak(Fmag[:, j])
            cone = result.cone_deg[j]
            if types[j] == "spherical":  # an interaction angle means something only about a socket axis
                a = _peak(result.interaction_angle_deg[:, j])
                angle = [f"{result.interaction_angle_deg[a, j]:.4f}", f"{t[a]:.3f}"]
            else:
                angle = ["-", "-"]
            rows.append([name, f"{Fmag[k, j]:.4f}", f"{t[k]:.3f}", *angle,
                         "-" if not np.isfinite(cone) else f"{cone:g}"])
        else:
            rows.append([name, "-", "-", "-", "-", "-"])
    lines += ["", table(["joint", "peak |F| N", "at t s", "max angle deg", "at t s", "cone deg"], rows)]
    bad = np.flatnonzero(~found)
    soft = np.flatnonzero(result.status == "softened")
    lines.append("")
    if len(bad):
        lines.append(f"no valid answer at {len(bad)} of {len(t)} instants:")
        for k in bad[:20]:
            lines.append(f"  t = {t[k]:.3f} s  {result.status[k]}: {printable(result.message[k])}")
        if len(bad) > 20:
            lines.append(f"  ... and {len(bad) - 20} more")
    else:
        lines.append(f"all {len(t)} instants solved")
    if len(soft):
        lines.append(f"softened at {len(soft)} instants (largest widening "
                     f"{np.max(result.softened_deg):.4g} deg)")
    tm, ts = result.time_model_s * 1e3, result.time_solve_s * 1e3
    lines.append(f"time per instant: model {np.median(tm):.3f} ms, solve {np.median(ts):.3f} ms "
                 f"(median; mean {np.mean(tm + ts):.3f} ms total)")
    # which stage of the solver chain answered (its first stage: 'ipm>polish' counts as ipm)
    if any(str(s) for s in result.stage):
        lines.append(stage_counts(result))
    return "\n".join(lines)


# what each answering stage's ``iterations`` count (summed with the least-norm stage's, if it ran)
ITERATION_UNITS = {"warm_active_set": "KKT solves", "dual_active_set": "Newton steps and KKT solves",
                   "ipm": "interior-point iterations",
                   "proxqp": "ProxQP iterations", "sqp_polish": "SQP and ProxQP iterations",
                   "clarabel": "Clarabel iterations"}


def stage_counts(result) -> str:
    """Which stage answered how many instants, with the median of what its iterations count:
    ``answered by warm_active_set at 99 instants (median 2 KKT solves), ipm at 2 (median 14
    interior-point iterations)``. Where the objective is a constant (``flat_objective``), the stage
    that answered its least-norm feasible problem, after a line that says so."""
    flat = f"{FLAT_OBJECTIVE_STAGE}>"
    first = np.array([str(s).removeprefix(flat).split(">")[0] for s in result.stage])
    its = np.asarray(result.iterations)
    asked = first != ""  # (an instant at which the model is undefined, status error, reached no stage)
    first, its = first[asked], its[asked]
    parts = []
    names, counts = np.unique(first, return_counts=True)
    for k, (name, count) in enumerate(sorted(zip(names, counts), key=lambda nc: (-nc[1], nc[0]))):
        unit = ITERATION_UNITS.get(name, "iterations")
        where = f"{count} instants" if k == 0 else f"{count}"
        parts.append(f"{name} at {where} (median {np.median(its[first == name]):.0f} {unit})")
    line = "answered by " + ", ".join(parts) if parts else "no instant"
    if any(str(s).startswith(flat) for s in result.stage):
        line = ("the objective is a constant (every weight is zero): the forces are the least-norm feasible "
                "ones\n" + line)
    return line
