"""``mcdm-pin verify RUN.npz ROBOT.yaml``: replay a solved run through the forward dynamics."""

from __future__ import annotations

from ..verify import (HOLDS, INTEGRATORS, ORDER, ConvergenceTable, convergence, planned_state,
                      problem_from_run, resolved_forces)
from ._common import UsageError, table


def format_table(conv: ConvergenceTable) -> str:
    return table(["substeps", "step s", "max |q - q_plan|", "order", "max |q_h - q_h/2|", "order"],
                  conv.rows())


def add(sub):
    """``mcdm-pin verify RUN.npz ROBOT.yaml [--integrator rk4|euler|semi-implicit] [--substeps N]``"""
    p = sub.add_parser("verify", help="replay a solved run through the forward dynamics (ABA) and show "
                                      "the tracking error as the step is halved")
    p.add_argument("run", help="results file (.npz) written by mcdm-pin solve --out")
    p.add_argument("robot", help="cable sidecar (YAML) of the robot the run was solved for")
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


def run(args) -> int:
    from ..results import TrajectoryResult
    from ..robot import Robot

    if args.substeps < 1:
        raise UsageError(f"--substeps: expected a positive integer, got {args.substeps}")
    if not 2 <= args.levels <= 12:
        raise UsageError(f"--levels: expected 2..12, got {args.levels}")
    robot = Robot.load(args.robot)
    result = TrajectoryResult.load(args.run)
    forces = None
    if args.resolve:
        from ..inverse_dynamics import InverseDynamics

        specs = robot.sidecar.trajectories
        if result.trajectory not in specs:
            raise UsageError(f"--resolve: the run's trajectory {result.trajectory!r} is not in "
                             f"{args.robot} (it has {', '.join(specs) or 'none'})")
        ident = InverseDynamics(robot, problem_from_run(robot, result), solver=result.solver or "proxqp")
        forces = resolved_forces(ident, planned_state(robot, specs[result.trajectory]))
    if args.window is not None and args.window < 1:
        raise UsageError(f"--window: expected a positive integer, got {args.window}")
    conv = convergence(robot, result, args.integrator, args.substeps, args.levels, args.hold, forces,
                        args.window)
    r0 = conv.reports[0]
    how = ("re-solved on the plan at every stage time" if forces is not None
           else f"{args.hold} between instants")
    print(f"{robot.name}: replay of {args.run} ({result.problem or 'unknown problem'})")
    print(f"forward dynamics: Pinocchio ABA, tau = -L(q)^T f, {args.integrator} (order "
          f"{ORDER[args.integrator]}), forces {how}; from the first solved "
          f"instant t = {r0.t[0]:g} s to t = {r0.t[-1]:g} s ({len(r0.t)} instants)"
          + (f", restarting from the plan every {args.window} instant(s)" if args.window else ""))
    print(f"open-loop growth rate at t = {r0.t[0]:g} s: {r0.growth_rate:.3g} 1/s (errors grow like "
          f"exp(rate * t) under force control)")
    if r0.stopped:
        print(r0.stopped)
    print()
    print(format_table(conv))
    print()
    if forces is not None:
        print(f"with re-solved forces the plan is the exact solution: max |q - q_plan| should shrink "
              f"by 2^{ORDER[args.integrator]} = {2 ** ORDER[args.integrator]} per halving down to "
              f"the solver's accuracy (equation of motion met to 1e-8 relative).")
        return 0
    print(f"max |q - q_plan| tends to the floor set by interpolating f between instants "
          f"({'O(dt^2)' if args.hold == 'linear' else 'O(dt)'} in the sample spacing), not by the "
          f"integrator; max |q_h - q_h/2| is the integrator's own error and should shrink by "
          f"2^{ORDER[args.integrator]} = {2 ** ORDER[args.integrator]} per halving.")
    return 0
