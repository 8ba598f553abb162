"""``mcdm-pin export-opensim ROBOT.yaml OUT.osim``: write a robot as an OpenSim model."""

from __future__ import annotations

from pathlib import Path

from ._common import UsageError, check_outputs, parse_float, printable
from ._files import robot_file


def add(sub):
    p = sub.add_parser("export-opensim", help="write a robot as an OpenSim model (.osim; needs the optional "
                                              "package opensim)")
    p.add_argument("robot", help="cable sidecar (YAML) or MuJoCo MJCF file")
    p.add_argument("out", help="the OpenSim model file to write (.osim)")
    p.add_argument("--optimal-force", metavar="F0",
                   help="optimal force of every cable's PathActuator, N (default: the largest f_max); a "
                        "control c means a tension c*F0, bounded by f_min/F0 .. f_max/F0")
    p.add_argument("--check", type=int, default=5, metavar="N",
                   help="read the written file back and compare its mass matrix, inverse dynamics, cable "
                        "lengths and moment arms with ours at N random states (default 5; 0: skip)")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    from ..export.opensim import describe, export_opensim
    from ..robot import Robot

    if Path(args.out).suffix.lower() != ".osim":
        raise UsageError(f"OUT: expected a file name ending in .osim, got {args.out!r}")
    robot = Robot.load(robot_file(args.robot))
    check_outputs([("OUT", args.out)], [("the sidecar", robot.sidecar.path), ("the URDF", robot.urdf_path)])
    f0 = None if args.optimal_force is None else parse_float(args.optimal_force, "--optimal-force")
    if f0 is not None and f0 <= 0:
        raise UsageError(f"--optimal-force: expected a force > 0 N, got {args.optimal_force!r}")
    spec = describe(robot)
    path = export_opensim(spec, args.out, f0)
    kinds = ", ".join(f"{j.name} ({j.kind})" for j in spec.joints)
    print(f"wrote {path}: {len(spec.bodies)} bodies, joints {kinds}, {len(spec.cables)} PathActuators")
    if spec.renamed:
        print(f"renamed for OpenSim ({len(spec.renamed)}; names keep A-Z a-z 0-9 _-.()[]#, see docs/opensim.md):")
        for kind, ours, theirs in spec.renamed:
            print(f"  {kind} {printable(repr(ours))} -> {theirs}")
    if args.check > 0:
        from ..export.opensim_eval import OpenSimModel, compare_with_pinocchio

        om = OpenSimModel(robot, path=path)
        print(f"optimal force {om.optimal_force:g} N; controls bounded by f_min/F0 .. f_max/F0")
        worst = compare_with_pinocchio(robot, om, args.check)
        print(f"checked against Pinocchio at {args.check} random states (largest relative difference):")
        for key, value in worst.items():
            print(f"  {key.replace('_', ' '):17s} {value:.1e}")
        if max(worst.values()) > 1e-9:
            print("warning: the written model differs from ours by more than 1e-9")
            return 1
    return 0
