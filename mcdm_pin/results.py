"""Per-instant and trajectory results, and their files (``.npz`` and ``.csv``).

``.npz`` keys (N instants, J physical joints, m cables, nv coordinates):

==========================  ============  =====================================================
key                         shape         meaning
==========================  ============  =====================================================
t                           (N,)          time, s
q                           (N, nv)       coordinates (rad or m; a native ball joint's rotation
                                          vector), Pinocchio joint order
configuration               (N, nq)       Pinocchio's configuration vector (equal to q when every
                                          joint has nq == nv; absent from older files)
qd, qdd                     (N, nv)       their first and second time derivatives
f                           (N, m)        cable forces, N (rows of NaN where no valid answer)
status                      (N,)          optimal, infeasible, max_iter, softened, inaccurate,
                                          budget; error: the model is undefined at that
                                          instant (a cable segment of zero length), the
                                          others are solved
message                     (N,)          what cannot be met, or why the instant has no
                                          answer (empty when optimal)
objective                   (N,)          objective value without the smoothing term
eom_residual                (N,)          relative equation-of-motion residual
joint_names                 (J,)          physical joints
joint_types                 (J,)          their types (spherical, revolute, ...; absent from
                                          older files)
cable_names                 (m,)          cables
coordinate_names            (nv,)         URDF joint of each coordinate
interaction_wrench          (N, J, 6)     [F; M] of parent on child, joint point, child frame
interaction_force_socket    (N, J, 3)     F in the socket (parent-side) frame
interaction_angle_deg       (N, J)        angle of F from the socket axis, degrees (NaN for
                                          joints without one: not spherical, no cone in the
                                          sidecar or the run)
cone_deg                    (J,)          cone half-angle used (NaN: no cone)
time_model_s, time_solve_s  (N,)          wall time of model evaluation and of solving, s
iterations                  (N,)          work of the stages that answered, summed: the
                                          active set's linear KKT solves (one per active
                                          set tried and Newton step), the interior-point,
                                          ProxQP (over cone rounds) or Clarabel iterations
rounds                      (N,)          QP solves (cone cut rounds + 1)
softened_deg                (N,)          cone widening applied in soften mode (0 otherwise)
needed_f_max                (N,)          infeasible by the bounds: smallest common f_max that
                                          would do, N (inf: none; NaN: not this case)
needed_cone_deg             (N,)          infeasible by the cones: smallest half-angle that would
                                          do, degrees (NaN: not this case)
unique                      (N,)          the optimum is provably unique (False: the least-norm
                                          optimum was picked among equally optimal forces, or
                                          no answer)
stage                       (N,)          the solver stage that answered (``ipm``,
                                          ``warm_active_set``, ``proxqp>polish``, ...)
tau_act                     (N, n_act)    hybrid robots: the actuated joints' torques (N m)
                                          or forces (N), one column per actuator component
                                          (n_act = 0 without actuators)
activation                  (N, m)        muscles (MJCF): each cable's activation, NaN on cables that are
                                          not muscles and at instants without an answer; (N, 0) without muscles
actuator_names              (n_act,)      ``JOINT`` or ``JOINT[i]`` per tau_act column
robot, problem, solver,     ()            strings describing the run
trajectory
problem_json                ()            the problem as data (``Problem.spec()`` as JSON;
                                          ``Problem.from_spec(robot, text)`` rebuilds it)
==========================  ============  =====================================================
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .exceptions import ResultsError
from .model.actuators import actuator_names


@dataclass
class InstantResult:
    """One instant's answer (see the module docstring for the meaning of each field)."""

    f: np.ndarray
    status: str
    objective: float
    eom_residual: float
    interaction_wrench: np.ndarray
    interaction_force_socket: np.ndarray
    interaction_angle_deg: np.ndarray
    iterations: int
    rounds: int
    time_model_s: float
    time_solve_s: float
    message: str = ""
    softened_deg: float = 0.0
    needed_f_max: float = float("nan")
    needed_cone_deg: float = float("nan")
    unique: bool = False
    stage: str = ""
    tau_act: np.ndarray = field(default_factory=lambda: np.zeros(0))  # actuated joints (hybrid robots)
    activation: np.ndarray = field(default_factory=lambda: np.zeros(0))  # muscles: (m,), NaN on other cables

    @property
    def found(self) -> bool:
        """A valid answer: ``optimal``, or ``softened`` (cones widened by :attr:`softened_deg`)."""
        return self.status in ("optimal", "softened")

    def __repr__(self) -> str:
        f = np.asarray(self.f, float)
        forces = (f"{len(f)} cable forces {np.min(f):.4g}..{np.max(f):.4g} N" if np.all(np.isfinite(f))
                  else f"no forces ({len(f)} cables)")
        why = f", {self.message!r}" if self.message else ""
        return (f"InstantResult({self.status}: {forces}, objective {self.objective:.6g}, "
                f"{len(self.interaction_wrench)} joints{why})")


_COLUMN_TYPES = dict(f=float, status=str, message=str, objective=float, eom_residual=float,
                     interaction_wrench=float, interaction_force_socket=float, interaction_angle_deg=float,
                     time_model_s=float, time_solve_s=float, iterations=int, rounds=int, softened_deg=float,
                     needed_f_max=float, needed_cone_deg=float, unique=bool, stage=str, tau_act=float,
                     activation=float)


def instant_columns(instants: list[InstantResult]) -> dict:
    """The instants' fields stacked into arrays, one per field (the trajectory-result columns)."""
    out = {name: np.array([getattr(r, name) for r in instants], dtype=dtype)
           for name, dtype in _COLUMN_TYPES.items()}
    for key in ("tau_act", "activation"):
        if out[key].ndim == 1:  # no instant, or no actuator / muscle: (N, 0)
            out[key] = out[key].reshape(len(instants), -1)
    return out


def concat_columns(parts: list[dict]) -> dict:
    """Columns of consecutive pieces of a trajectory, joined."""
    return {name: np.concatenate([p[name] for p in parts]) for name in _COLUMN_TYPES}


ARRAY_KEYS = ("t", "q", "qd", "qdd", "f", "status", "message", "objective", "eom_residual",
              "interaction_wrench", "interaction_force_socket", "interaction_angle_deg", "time_model_s",
              "time_solve_s", "iterations", "rounds", "softened_deg", "needed_f_max", "needed_cone_deg",
              "unique", "stage")
NAME_KEYS = ("joint_names", "cable_names", "coordinate_names")
META_KEYS = ("robot", "problem", "solver", "trajectory", "problem_json")
_OPTIONAL = {"needed_f_max": float("nan"), "needed_cone_deg": float("nan"), "unique": False, "stage": ""}


def socket_angles(angles, rob, cone_deg) -> np.ndarray:
    """``angles`` (N, J) with NaN in the columns of the joints of ``rob`` that have no socket axis:
    not spherical, no cone in the sidecar (``cone_deg``) and none in the run (``cone_deg`` here, NaN
    for none). A revolute joint's interaction force has no axis to lean from: no angle is stored."""
    angles = np.array(angles, dtype=float)
    cones = np.asarray(cone_deg, dtype=float).reshape(-1)
    if angles.ndim != 2 or angles.shape[1] != len(rob.joints):
        return angles
    for j, joint in enumerate(rob.joints):
        run_cone = j < len(cones) and np.isfinite(cones[j])
        if joint.type != "spherical" and joint.cone_deg is None and not run_cone:
            angles[:, j] = np.nan
    return angles


@dataclass
class TrajectoryResult:
    """Results over a trajectory (arrays as in the module docstring)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    f: np.ndarray
    status: np.ndarray
    message: np.ndarray
    objective: np.ndarray
    eom_residual: np.ndarray
    interaction_wrench: np.ndarray
    interaction_force_socket: np.ndarray
    interaction_angle_deg: np.ndarray
    time_model_s: np.ndarray
    time_solve_s: np.ndarray
    iterations: np.ndarray
    rounds: np.ndarray
    softened_deg: np.ndarray
    needed_f_max: np.ndarray
    needed_cone_deg: np.ndarray
    joint_names: np.ndarray
    cable_names: np.ndarray
    coordinate_names: np.ndarray
    cone_deg: np.ndarray
    robot: str = ""
    problem: str = ""
    solver: str = ""
    trajectory: str = ""
    unique: np.ndarray | None = None
    stage: np.ndarray | None = None
    problem_json: str = ""
    configuration: np.ndarray | None = None
    joint_types: np.ndarray | None = None
    tau_act: np.ndarray | None = None
    actuator_names: np.ndarray | None = None
    activation: np.ndarray | None = None

    def __post_init__(self):
        if self.tau_act is None:
            self.tau_act = np.zeros((len(self.t), 0))
        if self.activation is None:
            self.activation = np.zeros((len(self.t), 0))
        if self.actuator_names is None:
            self.actuator_names = np.array([], dtype=str)
        if self.unique is None:
            self.unique = np.zeros(len(self.t), dtype=bool)
        if self.stage is None:
            self.stage = np.full(len(self.t), "", dtype=str)
        if self.configuration is None:
            self.configuration = self.q

    def __repr__(self) -> str:
        """A few lines: what was run, how many instants have an answer, the peak forces (the arrays
        are attributes: ``run.f``, ``run.status``, ...)."""
        t, found = np.asarray(self.t, float), self.found
        span = f"t = {t[0]:g}..{t[-1]:g} s" if len(t) else "no instants"
        lines = [f"TrajectoryResult({self.robot or 'robot'}, trajectory {self.trajectory or '?'}: "
                 f"{len(t)} instants, {span}, solver {self.solver or '?'}",
                 f"  problem: {self.problem or '?'}"]
        bad = np.flatnonzero(~found)
        if len(bad):
            where = ", ".join(f"{t[k]:g}" for k in bad[:5]) + (", ..." if len(bad) > 5 else "")
            statuses = ", ".join(f"{n} {s}" for s, n in zip(*np.unique(self.status[bad], return_counts=True)))
            lines.append(f"  answered at {int(found.sum())} of {len(t)} instants; none at t = {where} s "
                         f"({statuses})")
        else:
            lines.append(f"  answered at all {len(t)} instants")
        if found.any():
            f = np.asarray(self.f, float)[found]
            F = self.force_magnitude[found]
            lines.append(f"  {f.shape[1]} cables: peak force {f.max():.4g} N; {F.shape[1]} joints: peak "
                         f"interaction force {F.max():.4g} N")
        return "\n".join(lines) + ")"

    @classmethod
    def from_instants(cls, rob, traj, instants: list[InstantResult], cone_deg, **meta):
        return cls.from_columns(rob, traj, instant_columns(instants), cone_deg, **meta)

    @classmethod
    def from_columns(cls, rob, traj, columns: dict, cone_deg, **meta):
        """From the per-instant fields stacked into arrays (:func:`instant_columns`)."""
        coords = (traj.q.copy() if rob.nq == rob.nv else
                  np.array([rob.coordinates(q) for q in traj.q]).reshape(len(traj.t), rob.nv))
        columns = dict(columns, interaction_angle_deg=socket_angles(columns["interaction_angle_deg"], rob, cone_deg))
        return cls(t=traj.t.copy(), q=coords, qd=traj.qd.copy(), qdd=traj.qdd.copy(), **columns,
                   configuration=traj.q.copy(),
                   joint_names=np.array(rob.joint_names, dtype=str),
                   cable_names=np.array(rob.cable_names, dtype=str),
                   coordinate_names=np.array(rob.coordinate_names, dtype=str),
                   joint_types=np.array([j.type for j in rob.joints], dtype=str),
                   actuator_names=np.array(actuator_names(rob), dtype=str),
                   cone_deg=np.asarray(cone_deg, dtype=float), **meta)

    def __len__(self) -> int:
        return len(self.t)

    @property
    def found(self) -> np.ndarray:
        """(N,) True at the instants with a valid answer (``optimal`` or ``softened``); the rows of
        the others are NaN in ``f``, the wrenches and the angles."""
        return np.isin(self.status, ("optimal", "softened"))

    @property
    def infeasible(self) -> np.ndarray:
        """Indices of the instants without a valid answer."""
        return np.flatnonzero(~self.found)

    @property
    def force_magnitude(self) -> np.ndarray:
        """(N, J) |F| of every joint's interaction force, N."""
        return np.linalg.norm(self.interaction_wrench[:, :, :3], axis=2)

    # ------------------------------------------------------------------------------------- files
    def save(self, path) -> Path:
        """Write ``.npz`` or ``.csv`` by the file's extension."""
        path = Path(path)
        if path.suffix not in (".npz", ".csv"):
            raise ResultsError(f"{path}: expected a .npz or .csv file name")
        try:
            return self.save_npz(path) if path.suffix == ".npz" else self.save_csv(path)
        except OSError as exc:
            raise ResultsError(f"{path}: cannot write the results ({exc.strerror or exc})") from None

    def save_npz(self, path) -> Path:
        path = Path(path)
        data = {k: getattr(self, k) for k in ARRAY_KEYS + NAME_KEYS + ("cone_deg", "configuration")}
        if self.joint_types is not None:
            data["joint_types"] = np.asarray(self.joint_types, dtype=str)
        data["tau_act"] = np.asarray(self.tau_act, dtype=float)
        data["activation"] = np.asarray(self.activation, dtype=float)
        data["actuator_names"] = np.asarray(self.actuator_names, dtype=str)
        data.update({k: np.array(getattr(self, k)) for k in META_KEYS})
        np.savez_compressed(path, **data)
        return path

    @classmethod
    def load(cls, path) -> "TrajectoryResult":
        path = Path(path)
        _check_archive(path)
        try:
            with np.load(path, allow_pickle=False) as z:
                missing = [k for k in ARRAY_KEYS + NAME_KEYS if k not in z.files and k not in _OPTIONAL]
                if missing:
                    raise ResultsError(f"{path}: not an mcdm-pin results file (missing {', '.join(missing)})")
                kw = {k: z[k] for k in ARRAY_KEYS + NAME_KEYS if k in z.files}
                for k, fill in _OPTIONAL.items():
                    kw.setdefault(k, np.full(len(kw["t"]), fill))
                kw["cone_deg"] = z["cone_deg"] if "cone_deg" in z.files else \
                    np.full(len(kw["joint_names"]), np.nan)
                for k in META_KEYS:
                    kw[k] = str(z[k]) if k in z.files else ""
                for k in ("configuration", "joint_types", "tau_act", "actuator_names", "activation"):
                    if k in z.files:
                        kw[k] = z[k]
        except FileNotFoundError:
            raise ResultsError(f"{path}: file not found") from None
        except (OSError, ValueError) as exc:
            raise ResultsError(f"{path}: cannot read the results ({exc})") from None
        return cls(**kw)

    def columns(self) -> dict[str, np.ndarray]:
        """The per-instant columns written to CSV, in order."""
        cols: dict[str, np.ndarray] = {"t": self.t}
        for prefix, arr in (("q", self.q), ("qd", self.qd), ("qdd", self.qdd)):
            for i, name in enumerate(self.coordinate_names):
                cols[f"{prefix}[{name}]"] = arr[:, i]
        for i, name in enumerate(self.cable_names):
            cols[f"f[{name}]"] = self.f[:, i]
        for i, name in enumerate(self.actuator_names):
            cols[f"tau_act[{name}]"] = self.tau_act[:, i]
        if self.activation.shape[1]:
            for i, name in enumerate(self.cable_names):
                if np.isfinite(self.activation[:, i]).any() or not self.found.any():
                    cols[f"a[{name}]"] = self.activation[:, i]
        cols.update(status=self.status, objective=self.objective, eom_residual=self.eom_residual)
        comps = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
        for j, name in enumerate(self.joint_names):
            for k, c in enumerate(comps):
                cols[f"{c}[{name}]"] = self.interaction_wrench[:, j, k]
            for k, c in enumerate(("Fx_socket", "Fy_socket", "Fz_socket")):
                cols[f"{c}[{name}]"] = self.interaction_force_socket[:, j, k]
            cols[f"angle_deg[{name}]"] = self.interaction_angle_deg[:, j]
        cols.update(time_model_s=self.time_model_s, time_solve_s=self.time_solve_s,
                    iterations=self.iterations, rounds=self.rounds, softened_deg=self.softened_deg,
                    needed_f_max=self.needed_f_max, needed_cone_deg=self.needed_cone_deg,
                    unique=self.unique, stage=self.stage, message=self.message)
        return cols

    def save_csv(self, path) -> Path:
        path = Path(path)
        cols = self.columns()
        with path.open("w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(cols.keys())
            for i in range(len(self.t)):
                w.writerow([_fmt(v[i]) for v in cols.values()])
        return path


def _check_archive(path: Path) -> None:
    """Refuse an ``.npz`` whose arrays would unpack beyond :data:`~mcdm_pin.limits.MAX_RESULTS_BYTES`
    (sizes from the archive's directory, before anything is read) or that is not one."""
    import zipfile

    from .limits import MAX_RESULTS_BYTES

    try:
        with zipfile.ZipFile(path) as zf:
            total = sum(info.file_size for info in zf.infolist())
    except FileNotFoundError:
        raise ResultsError(f"{path}: file not found") from None
    except IsADirectoryError:
        raise ResultsError(f"{path}: is a folder; expected a results file (.npz)") from None
    except (zipfile.BadZipFile, OSError) as exc:
        raise ResultsError(f"{path}: not a results file written by mcdm-pin solve --out (.npz): {exc}") from None
    if total > MAX_RESULTS_BYTES:
        raise ResultsError(f"{path}: its arrays unpack to {total} bytes; at most {MAX_RESULTS_BYTES} are read "
                           f"(docs/limits.md)")


def _fmt(x) -> str:
    if isinstance(x, (float, np.floating)):
        return repr(float(x))
    return str(x)
