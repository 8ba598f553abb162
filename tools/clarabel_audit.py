"""Every shipped robot's cold instants against Clarabel: does the default chain ever call an instant
infeasible that has an optimum, or report an optimum Clarabel does not reach?

    python tools/clarabel_audit.py [--robots 'robots/**/*.yaml'] [--instants 8] [--seed 1]

For each robot with a trajectory and each of cases 1-3 that applies to it (:mod:`stage_survey`'s
``robot_runs``), ``--instants`` states spread along its first trajectory, each as it is and, for a
robot without coupled coordinates, disturbed (the configuration moved by 0.05 rad or m per
coordinate on the manifold, the velocity scaled by a factor in [-2, 2], the acceleration by one in
[-3, 3] plus noise of 0.5): each solved cold (``reset()`` first) by the default chain and by
Clarabel's chain. A line per robot and case with the running counts; at the end every disagreement:
one found an optimum and the other did not, or the objectives differ by more than 1e-6 relative.
A state the model cannot evaluate (a cable of zero length) is counted and skipped.
"""

from __future__ import annotations

import argparse
import collections
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from stage_survey import robot_runs  # noqa: E402


def _states(robot, traj, instants: int, rng):
    """``(q, qd, qdd, label)`` per audited state (module docstring)."""
    import pinocchio as pin

    for k in np.unique(np.linspace(0, len(traj) - 1, instants).astype(int)):
        yield traj.q[k], traj.qd[k], traj.qdd[k], f"instant {k}"
        if robot.couplings is None:
            m = robot.model
            q = pin.integrate(m, np.asarray(traj.q[k], dtype=float), rng.normal(0.0, 0.05, m.nv))
            yield (q, traj.qd[k] * rng.uniform(-2, 2), traj.qdd[k] * rng.uniform(-3, 3) + rng.normal(0.0, 0.5, m.nv),
                   f"instant {k} disturbed")


def main(argv=None) -> int:
    from mcdm_pin import InverseDynamics
    from mcdm_pin.exceptions import StateError

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", default="robots/**/*.yaml", help="a glob relative to the repository")
    ap.add_argument("--instants", type=int, default=8, help="states along each first trajectory")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    bad, count = [], collections.Counter()
    for label, ident, traj in robot_runs(args.robots, (1, 2, 3)):
        ref = InverseDynamics.for_case(ident.robot, int(label.split()[-1]), solver="clarabel")
        for q, qd, qdd, where in _states(ident.robot, traj, args.instants, rng):
            try:
                ident.reset()
                ours = ident.solve(q, qd, qdd)
                ref.reset()
                theirs = ref.solve(q, qd, qdd)
            except StateError:
                count["model undefined"] += 1
                continue
            count["states"] += 1
            if ours.found != theirs.found:
                bad.append(f"{label}, {where}: ours {ours.status}, Clarabel {theirs.status} ({theirs.message[:80]})")
            elif ours.found:
                rel = abs(ours.objective - theirs.objective) / max(1.0, abs(theirs.objective))
                if rel > 1e-6:
                    bad.append(f"{label}, {where}: objective {ours.objective:.9g} against Clarabel's "
                               f"{theirs.objective:.9g} ({rel:.1e} relative; ours by {ours.stage})")
                else:
                    count["same optimum"] += 1
            else:
                count["both without an optimum"] += 1
        print(f"{label}: {dict(count)}, {len(bad)} disagreements", flush=True)
    print(f"\nin all: {dict(count)}; {len(bad)} disagreements")
    for line in bad:
        print(f"  {line}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
