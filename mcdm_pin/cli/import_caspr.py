"""``mcdm-pin import-caspr BODIES.xml CABLES.xml ...``: a CASPR model -> URDF + cable sidecar."""

from __future__ import annotations

from ..caspr import import_caspr


def add(sub):
    """``mcdm-pin import-caspr BODIES.xml CABLES.xml [--trajectories T.xml] [--cable-set ID] --out DIR``"""
    p = sub.add_parser("import-caspr", help="convert a CASPR model (bodies, cables, trajectories XML) "
                                            "into a URDF + sidecar")
    p.add_argument("bodies", help="CASPR *_bodies.xml")
    p.add_argument("cables", help="CASPR *_cables.xml")
    p.add_argument("--trajectories", help="CASPR *_trajectories.xml (every joint trajectory that can be "
                                          "converted is; the others are listed with the reason)")
    p.add_argument("--operational-spaces", metavar="FILE",
                   help="CASPR *_operational_spaces.xml (default: the one beside the bodies file): its set's "
                        "operational-space trajectories are solved by inverse kinematics (needs pin-pink: "
                        "pip install 'mcdm-pin[ik]')")
    p.add_argument("--operational-set", metavar="ID",
                   help="the operational set the trajectories are given in (default: the file's default)")
    p.add_argument("--trajectory", action="append", dest="trajectory_ids", metavar="ID",
                   help="convert only this trajectory id (repeatable)")
    p.add_argument("--cable-set", help="cable set id (default: the file's default_cable_set, or the first set "
                                       "with a cable when that one is empty)")
    p.add_argument("--out", required=True, help="output folder (sidecar and trajectory CSV files)")
    p.add_argument("--urdf-dir", help="folder of the URDF (default: --out)")
    p.add_argument("--name", help="robot name and file stem (default: from the bodies file name)")
    p.add_argument("--cone-deg", type=float, help="write this stability cone on every spherical joint")
    p.add_argument("--actuator-limit", type=float, metavar="N",
                   help="bound |tau| <= N (N m or N) on actuated joints' motors (default: unbounded, as in "
                        "CASPR; their weight 1 in the objective keeps them finite)")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    res = import_caspr(args.bodies, args.cables, args.out, trajectories_xml=args.trajectories,
                       cable_set=args.cable_set, name=args.name, trajectory_ids=args.trajectory_ids,
                       cone_deg=args.cone_deg, actuator_limit=args.actuator_limit, urdf_dir=args.urdf_dir,
                       operational_spaces_xml=args.operational_spaces, operational_set=args.operational_set)
    from ..robot import Robot

    robot = Robot.load(res.sidecar)
    for path in (res.urdf, res.sidecar, *res.csv_files.values()):
        print(f"wrote {path}")
    print(f"{robot!r}; cable set {res.cable_set!r}")
    for k, (a, b) in res.renamed_cables.items():
        print(f"note: cable {k} repeats the name {a!r}; renamed {b!r} (sidecar names must be unique)")
    for note in res.notes:
        print(f"note: {note}")
    if res.q_is_caspr_order:
        print("the coordinates are CASPR's q, in CASPR's order")
    else:
        print(f"the coordinates differ from CASPR's q: {', '.join(res.coordinate_names)}")
    if res.trajectories:
        kinds = [f"{tid} ({'csv' if tid in res.csv_files else 'quintic'})" for tid in res.trajectories]
        print("trajectories: " + ", ".join(kinds))
    for tid, sol in res.task_solutions.items():
        if tid in res.trajectories:
            print(f"trajectory {tid}: inverse kinematics, {len(sol.t)} samples; forward kinematics misses the "
                  f"poses by {sol.fk_error:.2g}, |J qd - yd| <= {sol.velocity_residual:.2g}, "
                  f"|J qdd + Jd qd - ydd| <= {sol.acceleration_residual:.2g}")
    for tid, reason in res.refused.items():
        print(f"refused trajectory {tid!r}: {reason}")
    return 0
