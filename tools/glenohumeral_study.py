"""The glenohumeral question on MyoSuite's arm: minimum activations along an abduction, without and with a
cone on the glenohumeral reaction force in the glenoid (scapula) frame.

    python tools/glenohumeral_study.py [--samples N] [--out docs/img]

Solves ``robots/myosuite/myoarm.yaml``'s ``abduction`` (101 instants by default) with ``sum a_i^2``
(:class:`~mcdm_pin.objectives.MinActivations`, the reserves' ``w tau^2`` beside it) and again with
:class:`~mcdm_pin.constraints.InteractionCone` on ``scapphant_r`` (the joint through which the scapula
carries the whole arm), each with the default solver chain and with Clarabel, and prints per case: the
instants solved, the largest objective difference between the two back-ends, the glenohumeral force and
its angle to the glenoid axis, and which muscles take over. Writes ``glenohumeral_abduction.png``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
GH = "scapphant_r"
# the rotator cuff and the deltoid in MyoSuite's arm (MoBL names)
GROUPS = {"rotator cuff": ("SUPSP", "INFSP", "SUBSC", "TMIN"), "deltoid": ("DELT1", "DELT2", "DELT3")}


def solve(robot, traj, cone: bool, solver: str):
    from mcdm_pin import InverseDynamics
    from mcdm_pin.constraints import InteractionCone
    from mcdm_pin.objectives import MinActivations
    from mcdm_pin.problem import Problem

    objective = MinActivations()
    constraints = [InteractionCone(GH)] if cone else []
    problem = Problem(robot, objective, constraints)
    return InverseDynamics(robot, problem, solver=solver).solve_trajectory(traj, progress=False)


def group_share(res, names):
    """Summed activation of each muscle group per instant."""
    cables = list(res.cable_names)
    return {g: np.nansum(res.activation[:, [cables.index(m) for m in ms if m in cables]], axis=1)
            for g, ms in GROUPS.items()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=101)
    ap.add_argument("--out", default=str(ROOT / "docs" / "img"))
    args = ap.parse_args(argv)
    from mcdm_pin.robot import Robot
    from mcdm_pin.trajectory import load_trajectory

    robot = Robot.load(ROOT / "robots" / "myosuite" / "myoarm.yaml")
    traj = load_trajectory(robot, "abduction").subsample(args.samples)
    j = robot.joint_names.index(GH)
    runs = {}
    for cone in (False, True):
        for solver in ("default", "clarabel"):
            runs[cone, solver] = solve(robot, traj, cone, solver)
    elev = np.degrees(traj.q[:, robot.coordinate_names.index("shoulder_elv_r")])
    print(f"myoarm abduction, {len(traj)} instants, shoulder_elv {elev[0]:.0f}..{elev[-1]:.0f} deg; cone "
          f"{robot.joint(GH).cone_deg:.2f} deg about {np.round(robot.joint(GH).socket_axis, 4).tolist()} "
          f"(scapula frame)")
    for cone in (False, True):
        ours, ref = runs[cone, "default"], runs[cone, "clarabel"]
        ok = ours.found & ref.found
        rel = np.abs(ours.objective[ok] - ref.objective[ok]) / np.maximum(1.0, np.abs(ref.objective[ok]))
        F = np.linalg.norm(ours.interaction_force_socket[:, j], axis=1)
        share = group_share(ours, GROUPS)
        print(f"\n{'with' if cone else 'without'} the cone: {int(ours.found.sum())}/{len(ours)} optimal "
              f"(Clarabel {int(ref.found.sum())}), statuses {sorted(set(ours.status))}; objective vs Clarabel: "
              f"max rel diff {rel.max(initial=0):.2e}; force vs Clarabel max "
              f"{np.nanmax(np.abs(ours.f - ref.f)):.2e} N")
        stages = {k: int(n) for k, n in zip(*np.unique(ours.stage, return_counts=True))}
        print(f"  answered by (default chain): {stages}")
        print(f"  sum a^2: median {np.nanmedian(ours.objective):.4f}, max {np.nanmax(ours.objective):.4f}; GH force "
              f"{np.nanmin(F):.0f}..{np.nanmax(F):.0f} N; angle to the glenoid axis "
              f"{np.nanmin(ours.interaction_angle_deg[:, j]):.1f}..{np.nanmax(ours.interaction_angle_deg[:, j]):.1f} deg")
        for g, s in share.items():
            print(f"  {g}: summed activation {np.nanmean(s):.3f} (mean), {np.nanmax(s):.3f} (max)")
    _plot(runs, elev, j, Path(args.out))
    return 0


def _plot(runs, elev, j, out: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.8))
    for cone, style in ((False, "-"), (True, "--")):
        res = runs[cone, "default"]
        label = "with GH cone" if cone else "without"
        ax[0].plot(elev, res.interaction_angle_deg[:, j], style, color="k", label=label)
        for (g, s), c in zip(group_share(res, GROUPS).items(), ("tab:red", "tab:blue")):
            ax[1].plot(elev, s, style, color=c, label=f"{g}, {label}")
        ax[2].plot(elev, res.objective, style, color="k", label=label)
    ax[0].axhline(runs[True, "default"].cone_deg[j], color="tab:red", lw=0.8, ls=":")
    ax[0].set(xlabel="shoulder elevation (deg)", ylabel="GH force angle to glenoid axis (deg)")
    ax[1].set(xlabel="shoulder elevation (deg)", ylabel="summed activation")
    ax[2].set(xlabel="shoulder elevation (deg)", ylabel="objective: sum a^2 (+ reserves)")
    for a in ax:
        a.legend(fontsize=7)
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "glenohumeral_abduction.png", dpi=110)
    print(f"\nwrote {out / 'glenohumeral_abduction.png'}")


if __name__ == "__main__":
    sys.exit(main())
