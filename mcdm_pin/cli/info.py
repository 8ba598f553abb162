"""``mcdm-pin info ROBOT.yaml``: a robot's links, joints, cables, a validation report and a check of
every trajectory (built in full, and solved at a handful of its instants)."""

from __future__ import annotations

import numpy as np

from ._common import UsageError, table
from ._files import robot_file


def add(sub):
    p = sub.add_parser("info", help="show a robot's links, joints, cables, a validation report and a "
                                    "check of every trajectory")
    p.add_argument("robot", help="cable sidecar (YAML) or MuJoCo MJCF file")
    p.add_argument("--samples", type=int, default=11,
                   help="instants of each trajectory at which the problem is solved (default 11, spread "
                        "evenly, first and last included; 0: only build the trajectories)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..robot import Robot
    from ..trajectory_checks import check_trajectories
    from ..validation import validation_report

    if args.samples < 0:
        raise UsageError(f"--samples: expected a number >= 0, got {args.samples}")
    robot = Robot.load(robot_file(args.robot))
    sc = robot.sidecar
    print(f"robot {robot.name}: {len(robot.joints)} joints, {robot.nv} DoF, {robot.m} cables"
          + (f" ({len(robot.cables.muscle_index)} muscles)" if robot.cables.muscles is not None else ""))
    if sc is not None:
        print(f"  sidecar  {sc.path}")
    if getattr(robot.source, "kind", None) == "mjcf":
        print(f"  mjcf     {robot.source.maps.source}")
    else:
        print(f"  urdf     {robot.urdf_path}" + (f"  ({sc.urdf})" if sc.urdf.startswith("package://") else ""))
    print(f"  gravity  {np.round(robot.model.gravity.linear, 6).tolist()} m/s^2")
    for note in robot.notes:
        print(f"  note     {note}")
    if sc is not None and sc.locked_joints:
        print(f"  locked   {len(sc.locked_joints)} URDF joints: "
              + ", ".join(f"{k}={v:g}" for k, v in sc.locked_joints.items()))
    print("\nlinks (MJCF bodies):" if sc is None or sc.mjcf_path is not None else "\nlinks (URDF frames):")
    print("  " + ", ".join(robot.link_names))
    print("\njoints:")
    rows = []
    for j in robot.joints:
        coords = ", ".join(robot.coordinate_names[i] for i in j.idx_v)
        axis = np.round(j.socket_axis, 6).tolist() if j.type == "spherical" or j.cone_deg is not None else "-"
        rows.append([j.name, j.type, j.nv, coords, axis, f"{j.alpha:g}",
                     f"{j.beta:g}", "-" if j.cone_deg is None else f"{j.cone_deg:g}"])
    source = "MJCF joints" if getattr(robot.source, "kind", None) == "mjcf" else "URDF joints"
    print(table(["joint", "type", "DoF", f"coordinates ({source})", "socket axis", "alpha", "beta",
                  "cone deg"], rows))
    print("\ncables:")
    rows = []
    muscles = set(robot.cables.muscle_index.tolist())
    for k, c in enumerate(robot.cables):
        bounds = ["muscle", "(FLV)"] if k in muscles else [f"{c.f_min:g}", f"{c.f_max:g}"]
        rows.append([c.name, *bounds, _route_text(c)])
    print(table(["cable", "f_min N", "f_max N", "route (link[point m], ~wrap~, |pulley|)"], rows))
    if robot.springs is not None:  # known tensions k (l - l0): mcdm_pin/model/springs.py
        print("\npassive springs (tension k (l - l0), known):")
        rows = [[s.name, f"{s.stiffness:g}", f"{s.rest_length:g}", "yes" if s.tension_only else "no", _route_text(s)]
                for s in robot.springs.springs]
        print(table(["spring", "k N/m", "l0 m", "tension only", "route"], rows))
    if sc is not None and sc.trajectories:
        print("\ntrajectories: " + ", ".join(
            f"{n} ({t.type}{'' if t.duration is None else f', {t.duration:g} s, dt {t.dt:g}'})"
            for n, t in sc.trajectories.items()))
    print("\nvalidation:")
    report = _inertia_report(robot) + validation_report(robot)
    if sc is not None and sc.trajectories:
        checks = check_trajectories(robot, samples=args.samples)
        report += [(c.level, c.text()) for c in checks]
    ok = True
    for level, text in report:
        print(f"  [{level}] {text}")
        ok &= level != "fail"
    return 0 if ok else 1


def _route_text(cable) -> str:
    """A route in one line: points as ``frame[x, y, z]``, wraps as ``~kind name r=radius~``, pulleys as
    ``|/divisor|``, rotating pulleys as ``(rotating pulley frame[entry] r=radius)``."""
    from ..model.cables import Pulley, RotatingPulley, Wrap

    parts = []
    for e in cable.route:
        if isinstance(e, RotatingPulley):
            parts.append(f"({'screw ' if e.screw else ''}rotating pulley {e.frame}{np.round(e.entry, 4).tolist()} "
                         f"r={e.radius:g})")
        elif isinstance(e, Wrap):
            parts.append(f"~{e.kind} {e.name or e.frame} r={e.radius:g}~")
        elif isinstance(e, Pulley):
            parts.append(f"|/{e.divisor:g}|")
        else:
            parts.append(f"{e.frame}{np.round(e.point, 4).tolist()}")
    return " -> ".join(parts)


def _inertia_report(robot) -> list[tuple[str, str]]:
    """A warning line when the robot's URDF carries inertias no body can have (accepted because its
    source, CASPR, ships them: :func:`mcdm_pin.urdf.check_urdf_inertias`)."""
    from ..urdf import moments_text, urdf_impossible_inertias

    bad = urdf_impossible_inertias(robot.urdf_path) if robot.urdf_path is not None else []
    if not bad:
        return []
    return [("warn", f"inertias as CASPR ships them: {len(bad)} link(s) have principal moments (kg m^2) that "
                     f"no body can have, breaking A + B >= C: {moments_text(bad)}; the answers are those of "
                     f"these numbers, not of physical bodies (docs/limits.md)")]

