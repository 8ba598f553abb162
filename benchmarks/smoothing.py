"""Effect of the smoothing term w |f - f_prev|^2 on the interaction objective (case 2).

For each weight: the largest jump of any cable force between consecutive instants, and the largest
relative excess of the interaction objective over its unsmoothed optimum.

    python benchmarks/smoothing.py [--robot robots/two_link_sr.yaml] [--trajectory traj2]
                                   [--weights 0,1e-6,1e-4,1e-2]
"""

from __future__ import annotations

import argparse

import numpy as np

from mcdm_pin import InverseDynamics, Robot, load_trajectory


def measure(robot, traj, weights, **options):
    base = InverseDynamics.for_case(robot, 2, **options).solve_trajectory(traj, progress=False)
    rows = []
    for w in weights:
        run = base if w == 0 else InverseDynamics.for_case(robot, 2, smoothing=w, **options) \
            .solve_trajectory(traj, progress=False)
        ok = run.found & base.found
        jumps = np.abs(np.diff(run.f, axis=0)).max(axis=1)
        excess = (run.objective[ok] - base.objective[ok]) / np.maximum(np.abs(base.objective[ok]), 1e-300)
        rows.append((w, float(np.nanmax(jumps)), float(np.nanmedian(jumps)), float(excess.max()),
                     int((~run.found).sum())))
    return rows


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robot", default="robots/two_link_sr.yaml")
    p.add_argument("--trajectory", default="traj2")
    p.add_argument("--weights", default="0,1e-8,1e-6,1e-4,1e-3,1e-2")
    p.add_argument("--alpha", type=float, help="alpha for every joint (default: the sidecar's)")
    args = p.parse_args(argv)
    robot = Robot.load(args.robot)
    traj = load_trajectory(robot, args.trajectory)
    options = {}
    if args.alpha is not None:
        options["alpha"] = {j: args.alpha for j in robot.joint_names}
    weights = [float(w) for w in args.weights.split(",")]
    print(f"{robot.name}, trajectory {args.trajectory}, case 2 (min interactions) + w |f - f_prev|^2")
    print("| w | largest jump N | median jump N | max relative objective excess | no answer |")
    print("|---|---|---|---|---|")
    for w, jmax, jmed, excess, bad in measure(robot, traj, weights, **options):
        print(f"| {w:g} | {jmax:.3f} | {jmed:.3f} | {excess:.2e} | {bad} |")


if __name__ == "__main__":
    main()
