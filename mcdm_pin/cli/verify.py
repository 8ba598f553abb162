"""``mcdm-pin verify ROBOT.yaml RUN.npz``: replay a solved run through the forward dynamics and judge
whether it converges to the plan (exit 0), diverges from it or does not converge (exit 1)."""

from __future__ import annotations

from ..verify import HOLDS, INTEGRATORS, ORDER, ConvergenceTable, convergence, judge
from ._common import UsageError, table
from ._files import robot_and_results


def format_table(conv: ConvergenceTable) -> str:
    return table(["substeps", "step s", "max |q - q_plan|", "order", "max |q_h - q_h/2|", "order"],
                 conv.rows())


def add(sub):
    """``mcdm-pin verify ROBOT.yaml RUN.npz [--integrator rk4|euler|semi-implicit] [--substeps N]``"""
    p = sub.add_parser("verify", help="replay a solved run through the forward dynamics (ABA), halve the "
                                      "step and judge whether the forces produce the planned motion")
    p.add_argument("robot", metavar="ROBOT", help="the robot's cable sidecar (YAML)")
    p.add_argument("run", metavar="RUN",
                   help="the results file (.npz) written by mcdm-pin solve --out (the two files may "
                        "also be given the other way round: they are told apart by their content)")
    p.add_argument("--integrator", choices=INTEGRATORS, default="rk4", help="default rk4")
    p.add_argument("--substeps", type=int, default=1,
                   help="integration steps per sample interval at the coarsest level (default 1)")
    p.add_argument("--levels", type=int, default=5, help="number of step halvings + 1 (default 5)")
    p.add_argument("--hold", choices=HOLDS, default="linear",
                   help="forces between instants: linear interpolation (default) or zero-order hold")
    p.add_argument("--window", type=int,
                   help="restart from the plan's state every N instants (for robots that are unstable "
                        "under force control; default: one replay over the whole run)")
    p.add_argument("--resolve", action="store_true",
                   help="re-solve the forces on the plan at every integrator stage time (dense forces) "
                        "instead of interpolating the run's: the plan is then the exact solution")
    p.set_defaults(func=run)
    return p


def _resolved(robot, result, robot_path):
    from ..inverse_dynamics import InverseDynamics
    from ..verify import planned_state, problem_from_run, resolved_forces

    specs = robot.sidecar.trajectories
    if result.trajectory not in specs:
        raise UsageError(f"--resolve: the run's trajectory {result.trajectory!r} is not in "
                         f"{robot_path} (it has {', '.join(specs) or 'none'})")
    ident = InverseDynamics(robot, problem_from_run(robot, result), solver=result.solver or "default")
    return resolved_forces(ident, planned_state(robot, specs[result.trajectory]))


def run(args) -> int:
    from ..exceptions import ResultsError
    from ..results import TrajectoryResult
    from ..robot import Robot

    if args.substeps < 1:
        raise UsageError(f"--substeps: expected a positive integer, got {args.substeps}")
    if not 2 <= args.levels <= 12:
        raise UsageError(f"--levels: expected 2..12, got {args.levels}")
    if args.window is not None and args.window < 1:
        raise UsageError(f"--window: expected a positive integer, got {args.window}")
    robot_path, run_path = robot_and_results(args.robot, args.run)
    robot = Robot.load(robot_path)
    result = TrajectoryResult.load(run_path)
    forces = _resolved(robot, result, robot_path) if args.resolve else None
    options = dict(integrator=args.integrator, substeps=args.substeps, hold=args.hold, forces=forces,
                   window=args.window)
    try:
        conv = convergence(robot, result, levels=args.levels, **options)
    except ResultsError as exc:  # name the file: the library's message cannot
        raise ResultsError(f"{run_path}: {exc}") from None
    r0 = conv.reports[0]
    how = ("re-solved on the plan at every stage time" if forces is not None
           else f"{args.hold} between instants")
    print(f"{robot.name}: replay of {run_path} ({result.problem or 'unknown problem'})")
    coupled = getattr(robot, "couplings", None)
    dynamics = ("Pinocchio ABA" if coupled is None else
                f"M, h from Pinocchio with the {len(coupled)} couplings' constraint forces (KKT)")
    act = " + S tau_act" if robot.actuators else ""
    print(f"forward dynamics: {dynamics}, tau = -L(q)^T f{act}, {args.integrator} (order "
          f"{ORDER[args.integrator]}), forces {how}; from the first solved "
          f"instant t = {r0.t[0]:g} s to t = {r0.t[-1]:g} s ({len(r0.t)} instants)"
          + (f", restarting from the plan every {args.window} instant(s)" if args.window else ""))
    print(f"open-loop growth rate: {conv.growth_rate:.3g} 1/s (largest of {min(5, len(r0.t))} instants, "
          f"at t = {conv.growth_at:g} s; errors grow like exp(rate * t) under force control)")
    if r0.stopped:
        print(r0.stopped)
    print()
    print(format_table(conv))
    print()
    verdict = judge(robot, result, conv, **options)
    print(verdict.text())
    return 0 if verdict.converged else 1
