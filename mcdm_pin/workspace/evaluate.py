"""One chunk of poses -> its results: the work a worker does.

Every pose is solved **cold**: the solver forgets every warm start before each pose (poses are
independent, and a chunk's answers must not depend on which poses it holds or in which order), with
the same problem as ``mcdm-pin solve`` (:meth:`InverseDynamics.for_case`) and no infeasibility
diagnosis (the two margins take its place, :mod:`.margins`).

The robot travels to the workers as data: the pickled :class:`~mcdm_pin.robot.Robot` (its Pinocchio
model, joints and cables; no file is read on a worker). A worker process unpickles it and builds the
solver once per robot and problem (:func:`solve_chunk` keeps them, one per thread).
"""

from __future__ import annotations

import hashlib
import json
import pickle
import threading
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..problem import Context
from ..solvers import STATUSES
from .errors import WorkspaceError
from .margins import pose_margins

STATUS_DTYPE = f"<U{max(len(s) for s in STATUSES)}"
COMPONENTS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")


@dataclass
class Setup:
    """The problem solved at every pose (as :func:`~mcdm_pin.problem.case_problem` and
    ``mcdm-pin solve`` take it), the constant rates, and whether to compute the margins.

    Attributes:
        case: 1, 2 or 3.
        cones: ``{joint: degrees}`` (case 3; default: the sidecar's ``cone_deg``).
        alpha, beta: ``{joint: weight}`` overriding the sidecar's (cases 2 and 3).
        frame: the cones' frame, ``socket`` or ``child``.
        solver: back-end name (``default``, ``compiled``, ``proxqp``, ``clarabel``).
        qd, qdd: constant coordinate rates (nv numbers each) at every pose; ``None``: zero (static).
        margins: compute ``needed_f_max`` and (case 3) ``needed_cone_deg`` at every pose.
    """

    case: int = 1
    cones: dict | None = None
    alpha: dict | None = None
    beta: dict | None = None
    frame: str = "socket"
    solver: str = "default"
    qd: list | None = None
    qdd: list | None = None
    margins: bool = True

    def describe(self) -> dict:
        return {k: v for k, v in asdict(self).items()}

    def key(self) -> str:
        return json.dumps(self.describe(), sort_keys=True)

    def identify(self, robot):
        """The :class:`~mcdm_pin.inverse_dynamics.InverseDynamics` of this setup on ``robot``."""
        from ..inverse_dynamics import InverseDynamics

        return InverseDynamics.for_case(robot, self.case, solver=self.solver, diagnose=False,
                                        alpha=self.alpha, beta=self.beta, cones=self.cones,
                                        frame=self.frame)

    def rates(self, robot) -> tuple[np.ndarray, np.ndarray]:
        out = []
        for name in ("qd", "qdd"):
            x = getattr(self, name)
            out.append(np.zeros(robot.nv) if x is None else robot.check_vector(x, name))
        return out[0], out[1]


class RobotBlob:
    """A robot as bytes (pickled), with a digest naming it in worker caches and in the store."""

    def __init__(self, robot):
        self.data = pickle.dumps(robot, protocol=pickle.HIGHEST_PROTOCOL)
        self.digest = robot_digest(robot)

    def load(self):
        return pickle.loads(self.data)


def robot_digest(robot) -> str:
    """sha256 of the robot's sidecar and URDF files (what a resumed run must share), or of the
    pickled robot when it was not loaded from files."""
    h = hashlib.sha256()
    paths = [getattr(getattr(robot, "sidecar", None), "path", None), getattr(robot, "urdf_path", None)]
    if all(p is not None and Path(p).is_file() for p in paths):
        for p in paths:
            h.update(Path(p).read_bytes())
    else:
        h.update(pickle.dumps(robot, protocol=pickle.HIGHEST_PROTOCOL))
    return h.hexdigest()


class PoseSolver:
    """Solves poses of one robot and setup, each cold (see the module docstring)."""

    def __init__(self, robot, setup: Setup):
        self.robot = robot
        self.setup = setup
        self.ident = setup.identify(robot)
        self.qd, self.qdd = setup.rates(robot)
        self.cones = bool(self.ident.problem.cone_constraints)
        self.context = Context(robot)

    def solve(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Results of poses ``q`` (n, nv): the store's per-pose variables."""
        robot = self.robot
        n, J, m = len(q), len(robot.joints), robot.m
        out = dict(q=robot.follow_couplings(np.asarray(q, dtype=float)), status=np.empty(n, dtype=STATUS_DTYPE),
                   objective=np.full(n, np.nan), f=np.full((n, m), np.nan),
                   interaction_wrench=np.full((n, J, 6), np.nan),
                   interaction_angle_deg=np.full((n, J), np.nan),
                   needed_f_max=np.full(n, np.nan), needed_cone_deg=np.full(n, np.nan))
        with self.ident.blas_limit():  # once for the chunk, not per pose
            for k in range(n):
                self._solve_pose(out, k)
        return out

    def _solve_pose(self, out: dict, k: int) -> None:
        """Pose ``k`` of ``out["q"]``, cold, into row ``k`` of ``out``."""
        self.ident.reset()
        res = self.ident.solve(out["q"][k], self.qd, self.qdd)
        out["status"][k] = res.status
        out["objective"][k] = res.objective
        out["f"][k] = res.f
        out["interaction_wrench"][k] = res.interaction_wrench
        out["interaction_angle_deg"][k] = res.interaction_angle_deg
        if self.setup.margins:
            out["needed_f_max"][k], out["needed_cone_deg"][k] = pose_margins(
                self.assemble(out["q"][k]), self.ident.solver, self.cones)

    def assemble(self, q):
        """The pose's assembled problem (``QPData``), for the margins."""
        terms = self.ident.evaluate(self.robot.pin_q(q), self.qd, self.qdd)  # configuration (nq)
        return self.ident.problem.assemble(terms, self.context)


_SOLVERS: dict = {}
_ROBOTS: dict = {}
_LOCK = threading.Lock()


def solve_chunk(blob: RobotBlob, setup: Setup, q: np.ndarray) -> dict[str, np.ndarray]:
    """A worker's task: the results of poses ``q`` (the robot unpickled and the solver built once
    per process and thread)."""
    key = (blob.digest, setup.key(), threading.get_ident())
    solver = _SOLVERS.get(key)
    if solver is None:
        with _LOCK:
            robot = _ROBOTS.get(blob.digest)
            if robot is None:
                robot = _ROBOTS[blob.digest] = blob.load()
        try:
            solver = _SOLVERS[key] = PoseSolver(robot, setup)
        except Exception as exc:  # noqa: BLE001 - reported to the client with its cause
            raise WorkspaceError(f"a worker cannot build the problem: {exc}") from exc
    return solver.solve(q)
