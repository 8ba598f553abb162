"""``import_caspr``: CASPR's XML files -> a URDF, a sidecar and trajectory CSV files, checked before
they are put in place.

Everything is written into a temporary folder first and loaded there (the robot, and every
trajectory); only when that succeeds are the files moved into the output folder, so a failed import
leaves the output folder as it was. A trajectory that cannot be converted is refused alone (its name
and reason are in :attr:`CasprImport.refused`) and the others are kept.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..exceptions import CasprError, InertiaWarning, McdmError
from .bodies import CasprBodies, read_bodies
from .cables import read_cables
from .pulleys import fill_screw_references
from .sampling import SamplingError, Samples, coordinates_from_caspr, sample, to_ours
from .trajectories import CasprOperationalTrajectory, CasprTrajectory, read_trajectories
from .writer import (GRAVITY, chains, csv_text, sidecar_cables, sidecar_joints, sidecar_springs, sidecar_text,
                     urdf_text)


@dataclass
class CasprImport:
    """What :func:`import_caspr` wrote.

    Attributes:
        urdf, sidecar: the files written; ``csv_files``: ``{trajectory id: CSV file}``.
        cable_set: the cable set converted.
        bodies: the bodies read (CASPR's links, joint types, ``q_initial``).
        layout: per CASPR link, the velocity indices of its physical joint in the model (chain order).
        nv, coordinate_names: the model's coordinates.
        trajectories: ``{id: CasprTrajectory}`` converted; ``refused``: ``{id: reason}`` not converted.
        notes: what the import remarked (normalised axes, segments that are not whole time steps).
        renamed_cables: ``{cable number: (CASPR name, our name)}`` for repeated names.
    """

    urdf: Path
    sidecar: Path
    cable_set: str
    bodies: CasprBodies
    layout: tuple
    nv: int
    coordinate_names: tuple[str, ...]
    csv_files: dict[str, Path] = field(default_factory=dict)
    trajectories: dict[str, CasprTrajectory] = field(default_factory=dict)
    refused: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    renamed_cables: dict = field(default_factory=dict)
    task_solutions: dict = field(default_factory=dict)  # {operational trajectory id: ik.TaskSolution}

    @property
    def q_index(self) -> np.ndarray:
        """(n,) ``coordinates[q_index] = q_caspr`` when every joint's coordinates are CASPR's (no free
        joint); raises :class:`CasprError` otherwise."""
        out = []
        for link, idx in zip(self.bodies.links, self.layout):
            if link.kind.sidecar == "free":
                raise CasprError(self.bodies.path, link.element, "a free joint's coordinates (position, "
                                 "rotation vector) are not CASPR's; use coordinates_from_caspr")
            by_coord = {spec[3]: int(i) for spec, i in zip(link.kind.chain, idx)}
            out.extend(by_coord[c] for c in range(link.n_q))
        return np.array(out, dtype=int)

    @property
    def q_is_caspr_order(self) -> bool:
        try:
            return bool(np.array_equal(self.q_index, np.arange(self.nv)))
        except CasprError:
            return False

    def coordinates_from_caspr(self, q_caspr) -> np.ndarray:
        """Our coordinates (nv) of CASPR's configuration ``q_caspr``."""
        return coordinates_from_caspr(self.bodies, self.layout, q_caspr, self.nv)

    def samples(self, trajectory_id: str) -> Samples:
        """CASPR's samples of a converted trajectory (:func:`~mcdm_pin.caspr.sampling.sample`; of an
        operational-space one, ``y`` and its rates: :func:`~mcdm_pin.caspr.sampling.sample_operational`)."""
        tr = self.trajectories[trajectory_id]
        if isinstance(tr, CasprOperationalTrajectory):
            from .sampling import sample_operational

            return sample_operational(tr)
        return sample(self.bodies, tr)

    def exact_trajectory(self, robot, trajectory_id: str):
        """The converted trajectory as a :class:`~mcdm_pin.trajectory.Trajectory` on ``robot`` (the
        imported robot), computed from CASPR's samples (not read back from a file)."""
        from ..trajectory import Trajectory

        if trajectory_id in self.task_solutions:  # solved by inverse kinematics at import
            sol = self.task_solutions[trajectory_id]
            return Trajectory(trajectory_id, sol.t, sol.q, sol.qd, sol.qdd)
        s = self.samples(trajectory_id)
        X, V, A = to_ours(self.bodies, self.layout, s, self.nv)
        Q = np.array([robot.configuration(x) for x in X]).reshape(len(s.t), robot.nq)
        return Trajectory(trajectory_id, s.t, Q, V, A)


def import_caspr(bodies_xml, cables_xml, out_dir, trajectories_xml=None, cable_set: str | None = None,
                 name: str | None = None, trajectory_ids=None, cone_deg: float | None = None,
                 actuator_limit: float | None = None, urdf_dir=None, urdf_name: str | None = None,
                 operational_spaces_xml=None, operational_set: str | None = None) -> CasprImport:
    """Convert CASPR model files into ``out_dir/NAME.yaml`` (+ CSVs) and ``urdf_dir/NAME.urdf``.

    Args:
        bodies_xml, cables_xml: CASPR's ``*_bodies.xml`` and ``*_cables.xml``.
        out_dir: folder of the sidecar and CSV files (created if missing; files of the same names are
            replaced).
        trajectories_xml: optional ``*_trajectories.xml``: every joint trajectory that can be converted
            is (two-point rest-to-rest quintics as sidecar ``quintic`` trajectories, the others as CSV
            files with exact ``qd:``/``qdd:`` columns); the others are listed in ``refused``.
        cable_set: the cable set id (default: the file's ``default_cable_set``).
        name: robot name and file stem (default: the bodies file name without ``_bodies.xml``).
        trajectory_ids: convert only these trajectory ids.
        cone_deg: stability cone written on every spherical joint (default: none).
        actuator_limit: a bound (N m or N) written on actuated joints' motors, ``-limit <= tau <=
            limit``; default: none, the motors are unbounded as in CASPR (``JointBase``: ``tau_min =
            -Inf``, ``tau_max = Inf``), kept finite by their weight 1 in the objective (CASPR's
            ``IDObjectiveMinQuadCableForce(ones(numActuatorsActive, 1))``).
        urdf_dir: folder of the URDF (default: ``out_dir``).
        urdf_name: the URDF's file stem and robot name (default: ``name``); the URDF depends on the
            bodies file only, so several cable sets of one model can share it.
        operational_spaces_xml: CASPR's ``*_operational_spaces.xml`` (default: the one beside the
            bodies file, if any): operational-space trajectories are solved by inverse kinematics on
            its set ``operational_set`` (default: the file's default) and written as CSV files
            (:mod:`.operational`).

    Raises:
        CasprError: the files are malformed or use an unsupported CASPR feature.
    """
    bodies = read_bodies(bodies_xml)
    cset = read_cables(cables_xml, bodies, cable_set)
    ops = None
    if trajectories_xml is not None:
        from .operational import choose

        ops = choose(bodies_xml, bodies, operational_spaces_xml, operational_set)
    tfile = read_trajectories(trajectories_xml, bodies, trajectory_ids, ops) if trajectories_xml is not None else None
    name = _check_options(bodies, bodies_xml, name, cone_deg, actuator_limit)
    urdf_name = _check_name(urdf_name or name, "urdf_name")
    out_dir = Path(out_dir)
    urdf_dir = out_dir if urdf_dir is None else Path(urdf_dir)
    source = (f"{Path(bodies_xml).name} + {Path(cables_xml).name} (cable set {cset.id!r})"
              + (f" + {Path(trajectories_xml).name}" if trajectories_xml is not None else ""))
    chs = chains(bodies)
    data = _sidecar_data(name, urdf_name, bodies, chs, cset, cone_deg, actuator_limit)
    tmp = _staging(out_dir, urdf_dir)
    try:
        (tmp / f"{urdf_name}.urdf").write_text(urdf_text(bodies, chs, urdf_name, Path(bodies_xml).name),
                                               encoding="utf-8")
        robot = _load(data, tmp, urdf_name)
        layout = tuple(robot.joint(link.ident).idx_v for link in bodies.links)
        if fill_screw_references(data["cables"], robot, bodies, layout):  # measured at q_initial
            robot = _load(data, tmp, urdf_name)
        result = CasprImport(urdf=urdf_dir / f"{urdf_name}.urdf", sidecar=out_dir / f"{name}.yaml", cable_set=cset.id,
                             bodies=bodies, layout=layout, nv=robot.nv,
                             coordinate_names=tuple(robot.coordinate_names),
                             notes=list(bodies.notes) + ([cset.note] if cset.note else []),
                             renamed_cables=dict(cset.renamed))
        if tfile is not None:
            result.notes += list(ops.notes) if any(isinstance(tr, CasprOperationalTrajectory)
                                                   for tr in tfile.trajectories.values()) else []
            result.refused.update(tfile.refused)
            _trajectories(result, tfile, data, tmp, name, urdf_name, robot)
            asked = [tid for tid in (trajectory_ids or ()) if tid in result.refused]
            if asked:  # a trajectory asked for by name is not refused quietly: the import fails
                raise CasprError(Path(trajectories_xml), f"trajectory {asked[0]!r}", result.refused[asked[0]])
        data["description"] = _description(result, source, cset)
        data["urdf"] = os.path.relpath(urdf_dir / f"{urdf_name}.urdf", out_dir).replace(os.sep, "/")
        (tmp / f"{name}.yaml").write_text(sidecar_text(data, source), encoding="utf-8")
        _move(tmp, result)
    except McdmError as exc:
        if isinstance(exc, CasprError) and str(tmp) not in str(exc):
            raise
        raise _caspr_error(exc, tmp, bodies, cset) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return result


def _sidecar_data(name, urdf_name, bodies, chs, cset, cone_deg, actuator_limit) -> dict:
    """The sidecar's content before the trajectories (written with :func:`.writer.sidecar_text`)."""
    data = {"version": 1, "name": name, "description": "", "urdf": f"{urdf_name}.urdf", "gravity": list(GRAVITY),
            "joints": sidecar_joints(chs, cone_deg, actuator_limit), "cables": sidecar_cables(bodies, cset)}
    if cset.springs:
        data["springs"] = sidecar_springs(bodies, cset)
    return data


def _staging(out_dir: Path, urdf_dir: Path) -> Path:
    """A new temporary folder beside ``out_dir`` (the import writes there and moves the files into place
    at the end), once both output folders are known to be writable."""
    for key, folder in (("out_dir", out_dir), ("urdf_dir", urdf_dir)):
        if folder.exists() and not folder.is_dir():
            raise CasprError(None, key, f"{folder} is a file; expected a folder (existing or to be made)")
    parent = _existing_parent(out_dir)
    for key, folder in (("--out", out_dir), ("--urdf-dir", urdf_dir)):
        _check_writable(folder, key)
    try:
        return Path(tempfile.mkdtemp(prefix=".import-caspr-", dir=parent))
    except OSError as exc:
        raise CasprError(None, "--out", f"{out_dir}: cannot be written ({exc.strerror or exc})") from None


def _check_writable(folder: Path, key: str) -> None:
    """``folder`` exists or can be made, and files can be written there: the nearest existing
    ancestor is a folder this process may write into."""
    path = folder.resolve()
    while not path.exists():
        path = path.parent
    if not path.is_dir():
        raise CasprError(None, key, f"{folder}: cannot be made, {path} is a file")
    if not os.access(path, os.W_OK | os.X_OK):
        raise CasprError(None, key, f"{folder}: cannot be written (no permission in {path})")


def _caspr_error(exc: McdmError, tmp: Path, bodies: CasprBodies, cset) -> CasprError:
    """An error met while loading the converted robot, named by the CASPR file and element it comes
    from (the converted files live in a temporary folder that is gone when the user reads this)."""
    text = str(exc).replace(str(tmp) + os.sep, "").replace(str(tmp), "")
    key = getattr(exc, "key", "") or ""
    detail = getattr(exc, "expected", None) or text
    m = re.match(r"(cables|springs)\[(\d+)\](?:\.route\[(\d+)\])?", key)
    of = {"cables": cset.cables, "springs": cset.springs}
    if m and int(m.group(2)) < len(of[m.group(1)]):
        cable = of[m.group(1)][int(m.group(2))]
        element = cable.element + (f"/attachments/attachment[{int(m.group(3)) + 1}]" if m.group(3) else "")
        return CasprError(cset.path, element, f"{detail} (converted: {key})")
    m = re.match(r"joints\.([^.\[]+)", key)
    links = {link.ident: link for link in bodies.links}
    if m and m.group(1) in links:
        return CasprError(bodies.path, links[m.group(1)].element, f"{detail} (converted: {key})")
    return CasprError(bodies.path, "", f"the converted model is refused: {text}")


def _check_options(bodies, bodies_xml, name, cone_deg, actuator_limit) -> str:
    if name is None:
        name = re.sub(r"(_bodies)?\.xml$", "", Path(bodies_xml).name) or "caspr_robot"
    _check_name(name, "--name")
    if cone_deg is not None and not 0 < cone_deg < 90:
        raise CasprError(None, "--cone-deg", f"expected an angle in (0, 90) degrees, got {cone_deg!r}")
    if actuator_limit is not None and not (math.isfinite(actuator_limit) and actuator_limit > 0):
        raise CasprError(None, "--actuator-limit", f"expected a finite bound > 0, got {actuator_limit!r}")
    return name


def _check_name(name: str, key: str) -> str:
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", name) or name.startswith("."):
        raise CasprError(None, key, f"expected letters, digits, '_', '-' or '.' (not first), got {name!r}")
    return name


def _existing_parent(path: Path) -> Path:
    path = path.resolve()
    while not path.is_dir():
        path = path.parent
    return path


def _load(data: dict, tmp: Path, urdf_name: str):
    """The robot of ``data`` with its URDF (and CSVs) in ``tmp``."""
    from ..robot import Robot
    from ..sidecar import parse_sidecar

    checked = dict(data, urdf=str(tmp / f"{urdf_name}.urdf"))
    with warnings.catch_warnings():  # (said already, per CASPR element: caspr/bodies.py)
        warnings.simplefilter("ignore", InertiaWarning)
        return Robot.from_sidecar(parse_sidecar(checked, path=tmp / f"{data['name']}.yaml", base_dir=tmp))


def _trajectories(result: CasprImport, tfile, data: dict, tmp: Path, name: str, urdf_name: str, robot) -> None:
    """Convert each trajectory, load it from what was written, and keep it or refuse it alone."""
    from ..trajectory import load_trajectory

    specs: dict = {}
    used: set[str] = set()
    for tid, tr in tfile.trajectories.items():
        csv_path = None
        try:
            spec, csv_path, notes = _convert_one(result, tr, tmp, name, robot, used)
            data["trajectories"] = dict(specs, **{tid: spec})
            load_trajectory(_load(data, tmp, urdf_name), tid)
        except (SamplingError, McdmError) as exc:
            result.refused[tid] = f"{tr.element}: {str(exc).replace(str(tmp) + os.sep, '')}"
            if csv_path is not None:
                csv_path.unlink()
            continue
        specs[tid] = spec
        result.trajectories[tid] = tr
        result.notes += [f"trajectory {tid!r}: {n}" for n in notes]
        if csv_path is not None:
            result.csv_files[tid] = result.sidecar.parent / csv_path.name
    data.pop("trajectories", None)
    if specs:
        data["trajectories"] = specs


def _convert_one(result, tr, tmp, name, robot, used):
    if isinstance(tr, CasprOperationalTrajectory):  # solved by inverse kinematics (caspr/operational.py)
        from .operational import solve

        s, sol, X = solve(result, tr, robot)
        result.task_solutions[tr.id] = sol
        V, A = sol.qd, sol.qdd
    else:
        s = sample(result.bodies, tr)
        if tr.rest_to_rest_single:
            p0, p1 = tr.points
            spec = {"type": "quintic", "q_start": _by_joint(result, robot, p0.q),
                    "q_end": _by_joint(result, robot, p1.q), "duration": float(s.t[-1] - s.t[0]),
                    "dt": tr.time_step, "spherical": "axis-angle"}
            return spec, None, s.notes
        X, V, A = to_ours(result.bodies, result.layout, s, result.nv)
    stem = f"{name}_{re.sub(r'[^A-Za-z0-9_.-]+', '_', tr.id)}"
    fname, k = f"{stem}.csv", 2
    while fname in used:
        fname, k = f"{stem}_{k}.csv", k + 1
    used.add(fname)
    path = tmp / fname
    path.write_text(csv_text(result.coordinate_names, s.t, X, V, A), encoding="utf-8")
    return {"type": "csv", "file": fname}, path, s.notes


def _by_joint(result, robot, q_caspr) -> dict:
    x = result.coordinates_from_caspr(q_caspr)
    return {j.name: [float(v) + 0.0 for v in x[j.idx_v]] for j in robot.joints}


def _description(result: CasprImport, source: str, cset) -> str:
    if result.q_is_caspr_order:
        order = "The coordinates are CASPR's q, in CASPR's order."
    else:
        free = [link.ident for link in result.bodies.links if link.kind.sidecar == "free"]
        order = ("The coordinates are not CASPR's q" + (f": the free joint(s) {', '.join(free)} take a position and "
                 f"a rotation vector instead of xyz Euler angles" if free else "")
                 + f" (coordinates {', '.join(result.coordinate_names)}).")
    renamed = "".join(f" Cable {k} is named {a!r} in CASPR like an earlier one; renamed {b!r}."
                      for k, (a, b) in cset.renamed.items())
    return (f"Imported from CASPR: {source}. {order} Spherical joints: alpha 1, beta 0, socket axis +z of the "
            f"parent frame; other joints: alpha = beta = 0.{renamed}{_kinds(cset)}"
            + (f" Note: {cset.note}." if cset.note else ""))


def _kinds(cset) -> str:
    """What the cables that are not ideal became (mcdm_pin/caspr/cables.py)."""
    out = ""
    kinds = sorted({c.kind for c in cset.cables} - {"cable_ideal"})
    for kind in kinds:
        names = [c.name for c in cset.cables if c.kind == kind]
        params = ", ".join(dict.fromkeys(k for c in cset.cables if c.kind == kind for k in c.stiffness))
        out += (f" Cables {', '.join(names)} are CASPR <{kind}>: active cables whose tension is the unknown within "
                f"[force_min, force_max]; their stiffness parameters ({params}) set the cable's stiffness, which "
                f"inverse dynamics does not use.")
    if cset.springs:
        out += (f" Springs {', '.join(s.name for s in cset.springs)} are CASPR <cable_passive_linear_spring>: "
                f"known tensions K (l - l0), not clipped at zero, on the right-hand side of the equation of motion.")
    return out


def _move(tmp: Path, result: CasprImport) -> None:
    """Put the checked files in place (the URDF into its folder, the rest beside the sidecar)."""
    try:
        result.sidecar.parent.mkdir(parents=True, exist_ok=True)
        result.urdf.parent.mkdir(parents=True, exist_ok=True)
        for f in sorted(tmp.iterdir()):
            dest = result.urdf if f.suffix == ".urdf" else result.sidecar.parent / f.name
            shutil.move(str(f), str(dest))
    except OSError as exc:
        where = exc.filename or result.sidecar.parent
        raise CasprError(None, "--out", f"{where}: cannot be written ({exc.strerror or exc})") from None
