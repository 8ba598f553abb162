"""``mcdm-pin import-caspr BODIES.xml CABLES.xml ...``: a CASPR model -> URDF + cable sidecar."""

from __future__ import annotations

from ..caspr import import_caspr


def add(sub):
    """``mcdm-pin import-caspr BODIES.xml CABLES.xml [--trajectories T.xml] [--cable-set ID] --out DIR``"""
    p = sub.add_parser("import-caspr", help="convert a CASPR model (bodies, cables, trajectories XML) "
                                            "into a URDF + sidecar")
    p.add_argument("bodies", help="CASPR *_bodies.xml")
    p.add_argument("cables", help="CASPR *_cables.xml")
    p.add_argument("--trajectories", help="CASPR *_trajectories.xml (quintic trajectories)")
    p.add_argument("--trajectory", action="append", dest="trajectory_ids", metavar="ID",
                   help="convert only this trajectory id (repeatable)")
    p.add_argument("--cable-set", help="cable set id (default: the file's default_cable_set)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--name", help="robot name and file stem (default: from the bodies file name)")
    p.add_argument("--cone-deg", type=float, help="write this stability cone on every spherical joint")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    res = import_caspr(args.bodies, args.cables, args.out, trajectories_xml=args.trajectories,
                       cable_set=args.cable_set, name=args.name, trajectory_ids=args.trajectory_ids,
                       cone_deg=args.cone_deg)
    from ..robot import Robot

    robot = Robot.load(res.sidecar)
    print(f"wrote {res.urdf}")
    print(f"wrote {res.sidecar}")
    for path in res.csv_files.values():
        print(f"wrote {path}")
    print(f"{robot!r}; cable set {res.cable_set!r}")
    for k, (a, b) in res.renamed_cables.items():
        print(f"note: cable {k} repeats the name {a!r}; renamed {b!r} (sidecar names must be unique)")
    if res.q_is_caspr_order:
        print("q lines up with CASPR's q")
    else:
        print(f"q order differs from CASPR's: q[q_index[i]] = q_caspr[i], q_index = {res.q_index.tolist()}")
    if res.trajectories:
        kinds = [f"{tid} ({'csv' if tid in res.csv_files else 'quintic'})" for tid in res.trajectories]
        print("trajectories: " + ", ".join(kinds))
    return 0
