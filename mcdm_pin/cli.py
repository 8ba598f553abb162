"""Command line: argument parsing only; every command calls the library.

``mcdm-pin info ROBOT.yaml`` and ``mcdm-pin solve ROBOT.yaml --trajectory NAME ...``; other modules add
their own sub-commands through :data:`COMMANDS`. Errors exit with status 2 and one line on stderr.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from .exceptions import McdmError


class UsageError(McdmError):
    """Bad command-line arguments."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage block
        raise UsageError(f"{self.prog}: {message} (see --help)")


# ---------------------------------------------------------------------------------------- helpers
def _parse_pairs(text: str, option: str, allow_all: bool = False) -> dict[str, str]:
    out = {}
    for item in text.split(","):
        item = item.strip()
        if not item:
            continue
        if "=" not in item:
            raise UsageError(f"{option}: expected NAME=VALUE[,NAME=VALUE...], got {item!r}")
        k, v = item.split("=", 1)
        out[k.strip()] = v.strip()
    if not out:
        raise UsageError(f"{option}: expected NAME=VALUE[,NAME=VALUE...], got {text!r}")
    return out


def _float(text: str, option: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise UsageError(f"{option}: expected a number, got {text!r}") from None
    if not np.isfinite(x):
        raise UsageError(f"{option}: expected a finite number, got {text!r}")
    return x


def _check_joint(robot, name: str, option: str):
    if name not in robot.joint_names:
        raise UsageError(f"{option}: unknown joint {name!r}; expected one of {', '.join(robot.joint_names)}")


def parse_weights(robot, text: str | None):
    """``JOINT=ALPHA[:BETA],...`` -> (alpha dict, beta dict)."""
    if not text:
        return None, None
    alpha, beta = {}, {}
    for name, value in _parse_pairs(text, "--weights").items():
        _check_joint(robot, name, "--weights")
        a, _, b = value.partition(":")
        alpha[name] = _float(a, f"--weights {name}")
        if b:
            beta[name] = _float(b, f"--weights {name}")
        for v in (alpha[name], beta.get(name, 0.0)):
            if v < 0:
                raise UsageError(f"--weights {name}: weights must be >= 0, got {value!r}")
    return alpha, beta


def parse_cones(robot, text: str | None):
    """``JOINT=DEG,...`` or ``all=DEG`` -> {joint: degrees}."""
    if not text:
        return None
    out = {}
    for name, value in _parse_pairs(text, "--cone").items():
        deg = _float(value, f"--cone {name}")
        if not 0.0 < deg < 90.0:
            raise UsageError(f"--cone {name}: expected an angle in (0, 90) degrees, got {value!r}")
        if name == "all":
            for j in robot.joints:
                if j.type == "spherical":
                    out[j.name] = deg
            if not out:
                raise UsageError("--cone all: the robot has no spherical joint")
        else:
            _check_joint(robot, name, "--cone")
            if robot.joint(name).type != "spherical":
                raise UsageError(f"--cone {name}: cones apply to spherical joints only")
            out[name] = deg
    return out


def _table(headers, rows) -> str:
    cells = [list(map(str, headers))] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = []
    for k, r in enumerate(cells):
        lines.append("  ".join(c.rjust(w) if k and _numeric(c) else c.ljust(w) for c, w in zip(r, widths)))
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(line.rstrip() for line in lines)


def _numeric(c: str) -> bool:
    try:
        float(c)
        return True
    except ValueError:
        return False


# ------------------------------------------------------------------------------------------- info
def add_info(sub):
    p = sub.add_parser("info", help="show a robot's links, joints, cables and a validation report")
    p.add_argument("robot", help="cable sidecar (YAML)")
    p.set_defaults(func=cmd_info)


def cmd_info(args) -> int:
    from .robot import Robot
    from .validation import validation_report

    robot = Robot.load(args.robot)
    sc = robot.sidecar
    print(f"robot {robot.name}: {len(robot.joints)} joints, {robot.nv} DoF, {robot.m} cables")
    print(f"  sidecar  {sc.path}")
    print(f"  urdf     {robot.urdf_path}" + (f"  ({sc.urdf})" if sc.urdf.startswith("package://") else ""))
    print(f"  gravity  {list(sc.gravity)} m/s^2")
    if sc.locked_joints:
        print(f"  locked   {len(sc.locked_joints)} URDF joints: "
              + ", ".join(f"{k}={v:g}" for k, v in sc.locked_joints.items()))
    print("\nlinks (URDF frames):")
    print("  " + ", ".join(robot.link_names))
    print("\njoints:")
    rows = []
    for j in robot.joints:
        coords = ", ".join(robot.coordinate_names[i] for i in j.idx_v)
        axis = np.round(j.socket_axis, 6).tolist() if j.type == "spherical" else "-"
        rows.append([j.name, j.type, j.nv, coords, axis, f"{j.alpha:g}",
                     f"{j.beta:g}", "-" if j.cone_deg is None else f"{j.cone_deg:g}"])
    print(_table(["joint", "type", "DoF", "coordinates (URDF joints)", "socket axis", "alpha", "beta",
                  "cone deg"], rows))
    print("\ncables:")
    rows = []
    for c in robot.cables:
        route = " -> ".join(f"{link}{np.round(p, 4).tolist()}" for link, p in zip(c.links, c.points))
        rows.append([c.name, f"{c.f_min:g}", f"{c.f_max:g}", route])
    print(_table(["cable", "f_min N", "f_max N", "route (link[point m])"], rows))
    if sc.trajectories:
        print("\ntrajectories: " + ", ".join(
            f"{n} ({t.type}{'' if t.type == 'csv' else f', {t.duration:g} s, dt {t.dt:g}'})"
            for n, t in sc.trajectories.items()))
    print("\nvalidation:")
    ok = True
    for level, text in validation_report(robot):
        print(f"  [{level}] {text}")
        ok &= level != "fail"
    return 0 if ok else 1


# ------------------------------------------------------------------------------------------ solve
def add_solve(sub):
    p = sub.add_parser("solve", help="cable forces along a trajectory (cases 1-3)")
    p.add_argument("robot", help="cable sidecar (YAML)")
    p.add_argument("--trajectory", "-t", required=True, help="a trajectory named in the sidecar")
    p.add_argument("--case", type=int, choices=(1, 2, 3), default=1,
                   help="1: min f^T f; 2: min interactions; 3: case 2 + stability cones (default 1)")
    p.add_argument("--weights", help="alpha (and beta) per joint: JOINT=ALPHA[:BETA],...")
    p.add_argument("--cone", help="cone half-angle per joint: JOINT=DEG,... or all=DEG (case 3)")
    p.add_argument("--frame", choices=("socket", "child"), default="socket",
                   help="frame of the cone's force (default socket, the source paper's)")
    p.add_argument("--solver", default="proxqp", help="proxqp (default) or clarabel (exact reference)")
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
    p.add_argument("--html", type=_html_file, metavar="FILE.html",
                   help="also write the 3-D view of the result as one self-contained HTML file")
    p.set_defaults(func=cmd_solve)
    return p


def run_solve(args):
    """Build and run the problem from parsed ``solve`` arguments; return (robot, result)."""
    from .inverse_dynamics import InverseDynamics
    from .robot import Robot
    from .trajectory import load_trajectory

    robot = Robot.load(args.robot)
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
    from .problem import case_problem
    problem = case_problem(robot, args.case, alpha=alpha, beta=beta, cones=cones, frame=args.frame,
                           smoothing=args.smoothing)
    ident = InverseDynamics(robot, problem, solver=args.solver, soften=args.soften,
                            diagnose=not args.no_diagnosis)
    if args.workers < 1:
        raise UsageError(f"--workers: expected a positive number, got {args.workers}")
    result = ident.solve_trajectory(traj, progress=False if args.quiet else None, workers=args.workers)
    result.problem = f"case {args.case}: " + result.problem
    return robot, result


def cmd_solve(args) -> int:
    for out in args.out:
        if Path(out).suffix not in (".npz", ".csv"):
            raise UsageError(f"--out: expected a .npz or .csv file name, got {out!r}")
    robot, result = run_solve(args)
    print(summary(result))
    for out in args.out:
        path = result.save(out)
        print(f"wrote {path}")
    for hook in POST_SOLVE_HOOKS:
        hook(args, robot, result)
    return 0


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
            k = int(np.nanargmax(col))
            rows.append([name, f"{col[k]:.4f}", f"{t[k]:.3f}", f"{np.nanmin(col):.4f}"])
        else:
            rows.append([name, "-", "-", "-"])
    lines += ["", _table(["cable", "peak f N", "at t s", "min f N"], rows)]
    rows = []
    Fmag = result.force_magnitude
    for j, name in enumerate(result.joint_names):
        if np.any(np.isfinite(Fmag[:, j])):
            k = int(np.nanargmax(Fmag[:, j]))
            a = int(np.nanargmax(result.interaction_angle_deg[:, j]))
            cone = result.cone_deg[j]
            rows.append([name, f"{Fmag[k, j]:.4f}", f"{t[k]:.3f}",
                         f"{result.interaction_angle_deg[a, j]:.4f}", f"{t[a]:.3f}",
                         "-" if not np.isfinite(cone) else f"{cone:g}"])
        else:
            rows.append([name, "-", "-", "-", "-", "-"])
    lines += ["", _table(["joint", "peak |F| N", "at t s", "max angle deg", "at t s", "cone deg"], rows)]
    bad = np.flatnonzero(~found)
    soft = np.flatnonzero(result.status == "softened")
    lines.append("")
    if len(bad):
        lines.append(f"no valid answer at {len(bad)} of {len(t)} instants:")
        for k in bad[:20]:
            lines.append(f"  t = {t[k]:.3f} s  {result.status[k]}: {result.message[k]}")
        if len(bad) > 20:
            lines.append(f"  ... and {len(bad) - 20} more")
    else:
        lines.append(f"all {len(t)} instants solved")
    if len(soft):
        lines.append(f"softened at {len(soft)} instants (largest widening "
                     f"{np.max(result.softened_deg):.4g} deg)")
    tm, ts = result.time_model_s * 1e3, result.time_solve_s * 1e3
    lines.append(f"time per instant: model {np.median(tm):.3f} ms, solve {np.median(ts):.3f} ms "
                 f"(median; mean {np.mean(tm + ts):.3f} ms total), "
                 f"{np.median(result.iterations):.0f} solver iterations (median)")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------- main
COMMANDS = [add_info, add_solve]
from .caspr import add_import_caspr  # noqa: E402
COMMANDS.append(add_import_caspr)
POST_SOLVE_HOOKS: list = []
from .cli_view import add_plot, add_view, html_file as _html_file, solve_html_hook  # noqa: E402
COMMANDS += [add_view, add_plot]
POST_SOLVE_HOOKS.append(solve_html_hook)
from .verify import add_verify  # noqa: E402
COMMANDS.append(add_verify)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="mcdm-pin", description="Inverse dynamics of multilink cable-driven "
                                                  "manipulators with joint interaction forces.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for add in COMMANDS:
        add(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        return int(args.func(args) or 0)
    except McdmError as exc:
        print(f"mcdm-pin: error: {exc}".replace("\n", " "), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("mcdm-pin: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
