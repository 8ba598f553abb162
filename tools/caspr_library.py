"""CASPR's model library -> the committed robots, the reference values, and the table of docs/caspr.md.

    python tools/caspr_library.py convert [--caspr DIR] [--check] [--models M ...]   # robots/caspr, urdf/caspr
    python tools/caspr_library.py reference [--caspr DIR] [--models M ...]  # tests/data/caspr_reference.npz
    python tools/caspr_library.py table                             # docs/caspr.md (plain clone)

``convert`` and ``reference`` read CASPR's XML files (default ``../shared/reference/caspr``: the 36 models
of CASPR's model list in ``library/`` and the SR arm in ``SR_model/``); ``table`` needs only the
repository. ``convert --check`` regenerates everything into a temporary folder and compares it byte for
byte with the committed files (exit 1 on any difference).

What is committed for each model (``robots/caspr/library.json`` records it): the URDF
(``urdf/caspr/MODEL.urdf``) and the sidecar of one cable set (the default one; when it cannot be
imported, the first that can), with its trajectories: every one that becomes a sidecar ``quintic``
(no file), the one the library table solves along, and, for the shipped robots (:data:`SHIPPED`), trajectory
CSV files, smallest first, up to a budget. The SR arm ships all three cable sets.
"""

from __future__ import annotations

import argparse
import filecmp
import json
import shutil
import sys
import tempfile
import zlib
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from mcdm_pin.caspr import cable_sets, import_caspr, read_bodies, read_cables  # noqa: E402
from mcdm_pin.exceptions import CasprError  # noqa: E402

DEFAULT_CASPR = REPO.parent / "shared" / "reference" / "caspr"
ROBOTS, URDF = Path("robots") / "caspr", Path("urdf") / "caspr"
CASPR_COMMIT = "a6971eeb65c4167ac856d147fc37443b07d0010d"
# the shipped robots (docs/caspr.md): bytes of trajectory CSV files committed with each (None: all of
# them); every other model keeps its sidecar quintics and the trajectory the library table solves along
SHIPPED = {"8S_neck": None, "SR_model": None, "IPAnema_1": 300_000, "Example_planar_XY": 300_000,
           "FASTKIT_Planar": 300_000}
# the trajectory the table solves along when the first sidecar quintic is not the one to show
TABLE_TRAJECTORY = {"Example_2R_planar_XZ": "setpoint_eMPC_finer"}
# reference states on each model's table trajectory, as fractions of its samples (0.47, not 0.5: many
# of CASPR's motions are symmetric, and their middle is a rest pose or a degenerate one)
TRAJECTORY_FRACTIONS = (0.2, 0.47, 0.8)


def models(caspr: Path) -> list[dict]:
    """CASPR's model list (library/models.json) and the SR arm, with their files."""
    lib = json.loads((caspr / "library" / "models.json").read_text())
    out = []
    for m in lib["models"]:
        files = {k: caspr / "library" / v.replace("<library>/", "") for k, v in m["files"].items()}
        source = {k: f"data/model_config/models{m['folder']}{Path(v).name}" for k, v in m["files"].items()}
        out.append(dict(model=m["dir"], caspr_name=m["caspr_name"], family=m["family"], files=files, source=source))
    sr = caspr / "SR_model"
    out.append(dict(model="SR_model", caspr_name="SR arm (2014 CSV files, converted to XML for mcdm-pin)",
                    family="MCDM", files={k: sr / f"SR_model_{k}.xml" for k in ("bodies", "cables", "trajectories")},
                    source={k: f"systems_prop/SR_model/*.csv @ 59451b6 (derived XML: SR_model_{k}.xml)"
                            for k in ("bodies", "cables", "trajectories")}))
    return out


# --------------------------------------------------------------------------------------- convert
def _try_sets(m: dict, tmp: Path) -> tuple[dict, str | None, str | None]:
    """Each cable set: ``"imported"`` or the refusal; the set to commit; the model's refusal."""
    files = m["files"]
    try:
        ids, default = cable_sets(files["cables"])
        read_bodies(files["bodies"])
    except CasprError as exc:
        return {}, None, _short(exc)
    status = {}
    for sid in ids:
        try:
            import_caspr(files["bodies"], files["cables"], tmp / "sets" / m["model"], cable_set=sid, name="probe")
            status[sid] = "imported"
        except CasprError as exc:
            status[sid] = _short(exc)
    order = ([default] if default in ids else []) + [s for s in ids if s != default]
    chosen = next((s for s in order if status[s] == "imported"), None)
    refusal = None if chosen else status.get(default, next(iter(status.values()), "no cable set"))
    return status, chosen, refusal


def _short(exc: CasprError) -> str:
    """A refusal without the absolute path of the file (it names the file)."""
    where = f"{Path(exc.path).name}: " if exc.path else ""
    return f"{where}{exc.element}: {exc.expected}" if exc.element else f"{where}{exc.expected}"


def _choose_trajectories(m: dict, probe) -> tuple[list[str], str | None, dict]:
    """Which converted trajectories to commit, the one the table solves along, and every
    trajectory's status."""
    status = {tid: f"refused: {reason.split(': ', 1)[-1] if tid.startswith('operational:') else reason}"
              for tid, reason in probe.refused.items()}
    quintic = [tid for tid in probe.trajectories if tid not in probe.csv_files]
    csvs = sorted(probe.csv_files, key=lambda tid: (probe.csv_files[tid].stat().st_size, tid))
    # the table solves along a joint-space trajectory: tests/caspr_newton.py samples it independently
    # (an operational one goes through our inverse kinematics first)
    joint = [tid for tid in quintic + csvs if not tid.startswith("operational:")]
    table = TABLE_TRAJECTORY.get(m["model"], joint[0] if joint else None)
    budget = SHIPPED.get(m["model"], 0)
    keep, used = list(quintic), 0
    for tid in csvs:
        size = probe.csv_files[tid].stat().st_size
        if tid == table or budget is None or used + size <= budget:
            keep.append(tid)
            used += size if tid != table else 0
    for tid in probe.trajectories:
        status[tid] = ("committed (sidecar quintic)" if tid in quintic else
                       "committed (CSV)" if tid in keep else
                       f"converted, not committed (CSV of {probe.csv_files[tid].stat().st_size // 1000} kB)")
    return [t for t in probe.trajectories if t in keep], table, status


def convert_model(m: dict, root: Path, tmp: Path) -> dict:
    files = m["files"]
    entry = dict(model=m["model"], caspr_name=m["caspr_name"], family=m["family"], source=m["source"])
    sets, chosen, refusal = _try_sets(m, tmp)
    entry.update(cable_sets=sets)
    if chosen is None:
        entry.update(status="refused", reason=refusal)
        return entry
    bodies = read_bodies(files["bodies"])
    actuated = any(link.actuated for link in bodies.links)
    kw: dict = {}  # import-caspr's defaults: CASPR's motors unbounded (weight 1), as CASPR leaves them
    probe = import_caspr(files["bodies"], files["cables"], tmp / "probe" / m["model"], cable_set=chosen,
                         trajectories_xml=files["trajectories"], **kw)
    keep, table, tstatus = _choose_trajectories(m, probe)
    out, urdf = root / ROBOTS / m["model"], root / URDF
    res = import_caspr(files["bodies"], files["cables"], out, cable_set=chosen, trajectories_xml=files["trajectories"],
                       trajectory_ids=keep, urdf_dir=urdf, name=m["model"], **kw)
    extra = []
    if m["model"] == "SR_model":  # the paper's arm: every cable set
        for sid in sets:
            if sid != chosen:
                import_caspr(files["bodies"], files["cables"], out, cable_set=sid, trajectories_xml=files["trajectories"],
                             urdf_dir=urdf, name=f"{m['model']}_{sid}", urdf_name=m["model"])
                extra.append(f"{ROBOTS}/{m['model']}/{m['model']}_{sid}.yaml")
    entry.update(status="imported", cable_set=chosen, became=became(bodies, _chosen_set(files, bodies, chosen)), sidecar=f"{ROBOTS}/{m['model']}/{m['model']}.yaml",
                 other_sidecars=extra, urdf=f"{URDF}/{m['model']}.urdf", trajectories=tstatus, table_trajectory=table,
                 actuated=actuated, actuator_limit=None,
                 joint_types=sorted({link.joint_type for link in bodies.links}), notes=list(res.notes),
                 links=[link.ident for link in bodies.links])
    return entry


def _chosen_set(files, bodies, chosen):
    """The chosen cable set as import-caspr reads it without --cable-set (with its note) when that is
    the one chosen, else as asked for."""
    try:
        cset = read_cables(files["cables"], bodies)
    except CasprError:
        cset = None
    return cset if cset is not None and cset.id == chosen else read_cables(files["cables"], bodies, chosen)


def became(bodies, cset) -> list[str]:
    """What the model's cables, springs and motors became (docs/caspr.md's table)."""
    out = []
    kinds: dict = {}
    for c in cset.cables:
        kinds.setdefault(c.kind, []).append(c.name)
    for kind, names in kinds.items():
        if kind != "cable_ideal":
            out.append(f"{len(names)} <{kind}> as cables (tension unknown in [force_min, force_max]; stiffness "
                       f"not used by inverse dynamics)")
    if cset.springs:
        out.append(f"{len(cset.springs)} passive spring(s) (known tension K (l - l0), right-hand side)")
    n_act = sum(link.n_q for link in bodies.links if link.actuated)
    if n_act:
        out.append(f"{n_act} unbounded joint motor(s) (unknowns, weight 1 as CASPR's)")
    if cset.note:
        out.append(cset.note)
    return out


def convert(caspr: Path, root: Path, only=None) -> list[dict]:
    """Convert every model, or with ``only`` (model names) those alone: their files are replaced and
    their entries of ``library.json`` rewritten, the others' kept."""
    entries = []
    old = {}
    if only:
        old = {e["model"]: e for e in json.loads((root / ROBOTS / "library.json").read_text())["models"]}
    with tempfile.TemporaryDirectory() as t:
        for m in models(caspr):
            if only and m["model"] not in only:
                entries.append(old[m["model"]])
                continue
            print(f"{m['model']} ...", flush=True)
            if only:
                shutil.rmtree(root / ROBOTS / m["model"], ignore_errors=True)
                (root / URDF / f"{m['model']}.urdf").unlink(missing_ok=True)
            entries.append(convert_model(m, root, Path(t)))
    lib = {"caspr": {"repository": "https://github.com/darwinlau/CASPR", "commit": CASPR_COMMIT,
                     "licence": "BSD 3-Clause, Copyright (c) 2017, Darwin Lau (LICENSE_CASPR.txt)"},
           "regenerate": "python tools/caspr_library.py convert", "models": entries}
    (root / ROBOTS / "library.json").write_text(json.dumps(lib, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return entries


def check(caspr: Path) -> int:
    """Regenerate into a temporary folder and compare with the committed files."""
    with tempfile.TemporaryDirectory() as t:
        convert(caspr, Path(t))
        bad = []
        for sub in (ROBOTS, URDF):
            new, old = Path(t) / sub, REPO / sub
            names = {p.relative_to(new) for p in new.rglob("*") if p.is_file()}
            names |= {p.relative_to(old) for p in old.rglob("*") if p.is_file() and p.name != "README.md"}
            for n in sorted(names):
                a, b = new / n, old / n
                if not (a.is_file() and b.is_file() and filecmp.cmp(a, b, shallow=False)):
                    bad.append(str(sub / n))
    print(f"{len(bad)} file(s) differ" + (": " + ", ".join(bad) if bad else ": the committed robots are "
                                          "regenerated byte for byte"))
    return 1 if bad else 0


# ------------------------------------------------------------------------------------- reference
def reference(caspr: Path, only=None) -> None:
    """The reference values of every imported model, or with ``only`` (model names) of those alone
    (the others' kept from the committed file)."""
    from mcdm_pin import Robot
    from tests import caspr_newton as cn
    from tests.caspr_library_check import reference_state

    lib = json.loads((REPO / ROBOTS / "library.json").read_text())
    by_model = {m["model"]: m for m in models(caspr)}
    out: dict = {}
    if only:
        with np.load(REPO / "tests" / "data" / "caspr_reference.npz", allow_pickle=False) as old:
            out = {k: old[k] for k in old.files if k.split(":", 1)[0] not in only}
    for entry in lib["models"]:
        if entry["status"] != "imported" or (only and entry["model"] not in only):
            continue
        files = by_model[entry["model"]]["files"]
        model = cn.Model.from_xml(files["bodies"], files["cables"], entry["cable_set"])
        robot = Robot.load(REPO / entry["sidecar"])
        states = _states(entry, model, files, robot)
        for s, st in enumerate(states):
            extra = {k: st[k] for k in ("t", "x", "v", "a") if k in st}
            for k, v in reference_state(model, st["q"], st["qd"], st["qdd"], **extra).items():
                out[f"{entry['model']}:{s}:{k}"] = v
        print(f"{entry['model']}: {len(states)} states", flush=True)
    np.savez_compressed(REPO / "tests" / "data" / "caspr_reference.npz", **out)


def _states(entry, model, files, robot) -> list[dict]:
    """The table trajectory's states (by time), the rest at q_initial when there is no trajectory, and
    one state with random rates (our state computed by the importer's conversion, stored)."""
    from tests import caspr_newton as cn
    from tests.caspr_library_check import ours_from_caspr

    states = []
    tid = entry["table_trajectory"]
    if tid is not None:
        t, Q, QD, QDD = cn.sample(model, cn.read_trajectory(files["trajectories"], tid, model.n))
        for frac in TRAJECTORY_FRACTIONS:
            k = int(round(frac * (len(t) - 1)))
            states.append(dict(t=t[k], q=Q[k], qd=QD[k], qdd=QDD[k]))
    else:
        q0 = np.concatenate([link.q_initial for link in model.links])
        states.append(dict(q=q0, qd=np.zeros(model.n), qdd=np.zeros(model.n)))
    rng = np.random.default_rng(zlib.crc32(entry["model"].encode()))
    q0 = np.concatenate([link.q_initial for link in model.links])
    states.append(dict(q=q0 + rng.uniform(-0.2, 0.2, model.n), qd=rng.uniform(-1, 1, model.n),
                       qdd=rng.uniform(-1, 1, model.n)))
    for st in states:
        if "t" not in st:
            st["x"], st["v"], st["a"] = ours_from_caspr(files["bodies"], robot, st["q"], st["qd"], st["qdd"])
    return states


# ----------------------------------------------------------------------------------------- main
def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("command", choices=("convert", "reference", "table"))
    p.add_argument("--caspr", type=Path, default=DEFAULT_CASPR, help="CASPR's files (library/, SR_model/)")
    p.add_argument("--check", action="store_true", help="convert: compare with the committed files")
    p.add_argument("--models", nargs="+", metavar="MODEL",
                   help="convert, reference: these models only (the others' files and values are kept)")
    args = p.parse_args(argv)
    if args.command == "table":
        from tools.caspr_table import write_table

        return write_table()
    if not (args.caspr / "library" / "models.json").is_file():
        print(f"caspr_library: CASPR's files not found in {args.caspr} (give --caspr DIR)", file=sys.stderr)
        return 2
    if args.command == "convert":
        if args.check:
            return check(args.caspr)
        if args.models:
            convert(args.caspr, REPO, only=set(args.models))
            return 0
        if (REPO / ROBOTS).exists():
            shutil.rmtree(REPO / ROBOTS)
        if (REPO / URDF).exists():
            shutil.rmtree(REPO / URDF)
        convert(args.caspr, REPO)
        _provenance()
        return 0
    reference(args.caspr, only=set(args.models or ()))
    return 0


def _provenance() -> None:
    """robots/caspr/README.md: where the robots come from, their licence, how to regenerate them."""
    from tools.caspr_table import provenance_text

    (REPO / ROBOTS / "README.md").write_text(provenance_text(), encoding="utf-8")


if __name__ == "__main__":
    sys.exit(main())
